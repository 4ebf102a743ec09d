#!/usr/bin/env python3
"""Write rough-plate.usda, rough-plate-constant.usda and rough-plate.png (issue 22).

The Cornell box of cbox-diffuse.usda (sublayered) with a metal plate on its floor. In
rough-plate.usda the plate's UsdPreviewSurface roughness reads the G channel of
rough-plate.png, scaled into [0.25, 0.75] (α = roughness² from 0.0625 to 0.5625): cells and
a smooth wave, so that the bake meets every level between. rough-plate-constant.usda is the
same plate at roughness 0.5, the texture's mean. Needs only the Python standard library;
deterministic. Run from this folder: python3 make_rough_plate.py
"""

import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SIDE = 128


def png(path, rows):
    """An 8-bit RGB PNG of `rows` (lists of (r, g, b) bytes)."""
    raw = b"".join(b"\0" + bytes(v for px in row for v in px) for row in rows)

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", len(rows[0]), len(rows), 8, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def roughness_map():
    """G from 0 to 255: 8 × 8 cells of hashed levels, plus a smooth wave across them."""
    rows = []
    for y in range(SIDE):
        row = []
        for x in range(SIDE):
            cell = ((x * 8 // SIDE) * 73 + (y * 8 // SIDE) * 151) % 17 / 16.0
            wave = 0.5 + 0.5 * math.sin(2 * math.pi * (x / SIDE * 3 + y / SIDE))
            g = round(255 * (0.5 * cell + 0.5 * wave))
            row.append((g, g, g))
        rows.append(row)
    return rows


PLATE = """
    def Mesh "plate" (
        prepend apiSchemas = ["MaterialBindingAPI"]
    )
    {{
        float3[] extent = [(-0.9, -0.99, -0.9), (0.9, -0.99, 0.9)]
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        rel material:binding = </cbox/Materials/plate>
        point3f[] points = [(-0.9, -0.99, 0.9), (0.9, -0.99, 0.9), (0.9, -0.99, -0.9), (-0.9, -0.99, -0.9)]
        texCoord2f[] primvars:uv = [(0, 0), (1, 0), (1, 1), (0, 1)] (
            interpolation = "vertex"
        )
        uniform token subdivisionScheme = "none"
    }}

    over "Materials"
    {{
        def Material "plate"
        {{
            token outputs:surface.connect = </cbox/Materials/plate/surface.outputs:surface>

            def Shader "surface"
            {{
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor = (0.95, 0.64, 0.54)
                float inputs:metallic = 1
{roughness}
                token outputs:surface
            }}
{texture}
        }}
    }}
"""

TEXTURE = """
            def Shader "reader"
            {
                uniform token info:id = "UsdPrimvarReader_float2"
                token inputs:varname = "uv"
                float2 outputs:result
            }

            def Shader "rough"
            {
                uniform token info:id = "UsdUVTexture"
                float4 inputs:bias = (0.25, 0.25, 0.25, 0)
                asset inputs:file = @rough-plate.png@
                float4 inputs:scale = (0.5, 0.5, 0.5, 1)
                token inputs:sourceColorSpace = "raw"
                float2 inputs:st.connect = </cbox/Materials/plate/reader.outputs:result>
                token inputs:wrapS = "repeat"
                token inputs:wrapT = "repeat"
                float outputs:g
            }"""


def stage(path, textured):
    roughness = (
        "                float inputs:roughness.connect = </cbox/Materials/plate/rough.outputs:g>"
        if textured
        else "                float inputs:roughness = 0.5"
    )
    body = PLATE.format(roughness=roughness, texture=TEXTURE if textured else "")
    with open(path, "w") as f:
        f.write('#usda 1.0\n(\n    defaultPrim = "cbox"\n    metersPerUnit = 1\n')
        f.write("    subLayers = [\n        @cbox-diffuse.usda@\n    ]\n")
        f.write('    upAxis = "Y"\n)\n\nover "cbox"\n{' + body + "}\n")


if __name__ == "__main__":
    png(os.path.join(HERE, "rough-plate.png"), roughness_map())
    stage(os.path.join(HERE, "rough-plate.usda"), True)
    stage(os.path.join(HERE, "rough-plate-constant.usda"), False)
