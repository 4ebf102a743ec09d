#!/usr/bin/env python3
"""Make the indirect-lit test scenes from the project's Cornell boxes.

Usage:  python3 make_indirect.py MITSUBA_DIR OUTPUT_DIR

Reads MITSUBA_DIR/cbox-{rough,glossy,diffuse}.gltf (tests/data/mitsuba/) and writes, for each
recipe below, a copy whose `light` quad is moved and turned and whose radiance is scaled so
that the light's power stays the Cornell box's (0.46 x 0.38 at the original radiance). Only
the light's four vertex positions (and its emission) change; every other byte of geometry and
every material is the source scene's. Standard library only, deterministic.

The recipes are the cases where indirect light is the whole image, as a user lights an
interior with a small bulb turned away from the view:

    ceiling-<src>  a 0.1 x 0.1 light 0.1 below the ceiling, facing the ceiling (+Y)
    wall-<src>     a 0.1 x 0.1 light 0.1 in front of the back wall, facing it (-Z)
"""
import base64
import json
import os
import struct
import sys

LIGHT_AREA = 0.46 * 0.38
SMALL = 0.05  # half side: 0.1 x 0.1


def quad(center, u, v):
    """Four corners, counter-clockwise seen from the front: front normal = u x v."""
    c = center
    return [[c[i] - u[i] - v[i] for i in range(3)], [c[i] + u[i] - v[i] for i in range(3)],
            [c[i] + u[i] + v[i] for i in range(3)], [c[i] - u[i] + v[i] for i in range(3)]]


RECIPES = {
    # u x v = +Y: u = +Z, v = +X.
    'ceiling': quad([0.0, 0.9, 0.0], [0.0, 0.0, SMALL], [SMALL, 0.0, 0.0]),
    # u x v = -Z: u = +Y, v = +X.
    'wall': quad([0.0, 0.1, -0.9], [0.0, SMALL, 0.0], [SMALL, 0.0, 0.0]),
}


def make(src_path, recipe):
    with open(src_path) as f:
        g = json.load(f)
    uri = g['buffers'][0]['uri']
    head, b64 = uri.split(',', 1)
    data = bytearray(base64.b64decode(b64))
    light_node = next(n for n in g['nodes'] if n.get('name') == 'light')
    mesh = g['meshes'][light_node['mesh']]
    prim = mesh['primitives'][0]
    acc = g['accessors'][prim['attributes']['POSITION']]
    view = g['bufferViews'][acc['bufferView']]
    assert acc['count'] == 4 and acc['componentType'] == 5126
    corners = RECIPES[recipe]
    # The source quad's triangles are (0,1,2), (2,3,0); its corner order is Mitsuba's
    # rectangle's, counter-clockwise from the front, as ours.
    offset = view.get('byteOffset', 0) + acc.get('byteOffset', 0)
    flat = [float(x) for p in corners for x in p]
    stored = struct.unpack('<12f', struct.pack('<12f', *flat))
    data[offset:offset + 48] = struct.pack('<12f', *flat)
    acc['min'] = [min(stored[i::3]) for i in range(3)]
    acc['max'] = [max(stored[i::3]) for i in range(3)]
    g['buffers'][0]['uri'] = head + ',' + base64.b64encode(bytes(data)).decode('ascii')
    scale = LIGHT_AREA / (2 * SMALL) ** 2
    mat = g['materials'][prim['material']]
    radiance = [round(c * scale, 6) for c in mat['extras']['mitsuba']['radiance']]
    m = max(radiance)
    mat['extras']['mitsuba']['radiance'] = radiance
    mat['emissiveFactor'] = [c / m for c in radiance]
    mat['extensions']['KHR_materials_emissive_strength']['emissiveStrength'] = m
    g['asset'].setdefault('extras', {})['indirect_recipe'] = (
        f'make_indirect.py {recipe}: light 0.1 x 0.1, corners {corners}, '
        f'radiance x{scale:.4f} (same power)')
    return g


def main():
    src, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    for recipe, base in [('ceiling', 'cbox-rough'), ('wall', 'cbox-glossy'),
                         ('ceiling', 'cbox-diffuse')]:
        g = make(os.path.join(src, base + '.gltf'), recipe)
        name = f'{recipe}-{base[5:]}'
        with open(os.path.join(out, name + '.gltf'), 'w') as f:
            json.dump(g, f, indent=1)
            f.write('\n')
        print(name)


if __name__ == '__main__':
    main()
