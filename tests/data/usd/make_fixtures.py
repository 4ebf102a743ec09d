#!/usr/bin/env python3
"""Author the USD test fixtures with Pixar's usd-core (`pip install usd-core`; run by hand, not
by CI; the outputs are committed next to this script).

- cbox-diffuse.usda / .usdc / .usdz: tests/data/mitsuba/cbox-diffuse.gltf as a Y-up stage in
  metres: the same triangles, vertex normals, explicit Mitsuba BSDFs (`mitsuba:*` attributes on
  the materials, as the glTF's extras), UsdPreviewSurface emission equal to the glTF's
  explicit area radiance, and the camera (focal length and vertical aperture giving the glTF's
  vertical field of view).
- cbox-diffuse-zup-cm.usda: the same scene Z-up in centimetres (coordinates turned and scaled,
  camera turned), which must import as its Y-up metre twin.
- composed.usda: a sublayer (cbox-diffuse.usda) and a reference to quad.usda's /quad, moved by
  a translate op.
- lights.usda: a RectLight (0.5 x 0.25, intensity 10, exposure 1, colour (1, 0.5, 0.25)) at
  (0, 1, 0) facing down, a normalized DiskLight (radius 0.1, intensity 3) at (-1, 0, 0), a
  SphereLight (radius 0.2, intensity 5) at (1, 0, 0) and a DistantLight (intensity 50000,
  angle 0.53) shining down.
- instancing.usda: a class /proto holding quad.usda's /quad as its child, instanced twice (at
  x = -0.5 and 0.5), and a guide-purpose and an invisible reference to the quad.
- missing-member.usdz: a usdz whose layer references gone.usda, which the archive lacks.
- animated.usda: quad.usda's /quad translated by (0, 0, 0) at time code 1 and (0.9, 0, 0) at 10
  (start 1, end 10).
- textured.usda + checker.png: a unit quad whose texture coordinates are the indexed primvar
  `uv`, read through a UsdPrimvarReader_float2 and a UsdTransform2d (scale 2, rotation 90°,
  translation (1, 0)); metallic 1; diffuseColor from the 2x2 sRGB checker's rgb, roughness from its g
  channel with scale 0.5 and bias 0.1 (raw), wrap clamp, and emissiveColor from its rgb with
  wrap black.
- dome.usda: a diffuse (0.5) UV-sphere mesh of radius 1 under a DomeLight of colour 0.5 and
  intensity 2 (radiance 1 from everywhere), with a camera on +Z.
- dome-sky.usda + sky.png: a diffuse (0.5) floor facing up under a DomeLight whose
  latitude-longitude map (64 x 32, sRGB PNG) is white above the horizon and black below;
  dome-sky-flipped.usda is the same with the light turned upside down (rotateX 180).
- roughness-test-lit.usda: roughness-test/RoughnessTest.usdz (which has no light and no
  camera) referenced under a stage with a rect light and a camera in front of its cards.
"""
import base64
import json
import math
import os
import struct

from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, UsdUtils, Vt

HERE = os.path.dirname(os.path.abspath(__file__))
GLTF = os.path.join(HERE, "..", "mitsuba", "cbox-diffuse.gltf")


def read_gltf(path):
    g = json.load(open(path))
    buffers = [base64.b64decode(b["uri"].split(",", 1)[1]) for b in g["buffers"]]

    def accessor(i):
        a = g["accessors"][i]
        view = g["bufferViews"][a["bufferView"]]
        data = buffers[view["buffer"]]
        offset = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        comps = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}[a["type"]]
        fmt = {5126: "f", 5125: "I", 5123: "H"}[a["componentType"]]
        size = struct.calcsize(fmt)
        stride = view.get("byteStride", size * comps)
        out = []
        for k in range(a["count"]):
            vals = struct.unpack_from("<" + fmt * comps, data, offset + k * stride)
            out.append(vals if comps > 1 else vals[0])
        return out

    return g, accessor


def author(path, z_up_cm):
    g, accessor = read_gltf(GLTF)
    stage = Usd.Stage.CreateNew(path)
    scale = 100.0 if z_up_cm else 1.0
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z if z_up_cm else UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 0.01 if z_up_cm else 1.0)

    def point(p):
        # Y-up metres to Z-up centimetres: (x, y, z) -> (x, -z, y) * 100.
        return Gf.Vec3f(p[0] * scale, -p[2] * scale, p[1] * scale) if z_up_cm else Gf.Vec3f(*p)

    def normal(n):
        return Gf.Vec3f(n[0], -n[2], n[1]) if z_up_cm else Gf.Vec3f(*n)

    root = UsdGeom.Xform.Define(stage, "/cbox")
    stage.SetDefaultPrim(root.GetPrim())
    materials = []
    for i, m in enumerate(g["materials"]):
        mat = UsdShade.Material.Define(stage, f"/cbox/Materials/{m['name']}")
        shader = UsdShade.Shader.Define(stage, f"/cbox/Materials/{m['name']}/surface")
        shader.CreateIdAttr("UsdPreviewSurface")
        pbr = m["pbrMetallicRoughness"]
        shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*pbr["baseColorFactor"][:3]))
        shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(pbr["roughnessFactor"])
        mitsuba = m["extras"]["mitsuba"]
        if mitsuba["type"] == "area":
            shader.CreateInput("emissiveColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*mitsuba["radiance"]))
            mitsuba = m["extras"]["mitsuba_bsdf"]
        mat.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
        prim = mat.GetPrim()
        prim.CreateAttribute("mitsuba:type", Sdf.ValueTypeNames.String).Set(mitsuba["type"])
        prim.CreateAttribute("mitsuba:reflectance", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*mitsuba["reflectance"]))
        materials.append(mat)
    for node in g["nodes"]:
        if "mesh" in node:
            gm = g["meshes"][node["mesh"]]
            prim = gm["primitives"][0]
            positions = accessor(prim["attributes"]["POSITION"])
            indices = accessor(prim["indices"])
            mesh = UsdGeom.Mesh.Define(stage, f"/cbox/{node['name'].replace('-', '_')}")
            mesh.CreatePointsAttr(Vt.Vec3fArray([point(p) for p in positions]))
            mesh.CreateFaceVertexCountsAttr(Vt.IntArray([3] * (len(indices) // 3)))
            mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(indices))
            mesh.CreateSubdivisionSchemeAttr("none")
            mesh.CreateDoubleSidedAttr(False)
            if "NORMAL" in prim["attributes"]:
                normals = accessor(prim["attributes"]["NORMAL"])
                mesh.CreateNormalsAttr(Vt.Vec3fArray([normal(n) for n in normals]))
                mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
            UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(materials[prim["material"]])
        elif "camera" in node:
            yfov = g["cameras"][node["camera"]]["perspective"]["yfov"]
            cam = UsdGeom.Camera.Define(stage, "/cbox/camera")
            focal = 50.0
            aperture = 2.0 * focal * math.tan(0.5 * yfov)
            cam.CreateFocalLengthAttr(focal)
            cam.CreateVerticalApertureAttr(aperture)
            cam.CreateHorizontalApertureAttr(aperture)
            t = node["translation"]
            if z_up_cm:
                # Local -Z (the view) along world +Y, local +Y (up) along world +Z.
                m = Gf.Matrix4d((1, 0, 0, 0), (0, 0, 1, 0), (0, -1, 0, 0),
                                (t[0] * scale, -t[2] * scale, t[1] * scale, 1))
                cam.AddTransformOp().Set(m)
            else:
                cam.AddTranslateOp().Set(Gf.Vec3d(*t))
    stage.GetRootLayer().Save()
    return stage


def main():
    base = os.path.join(HERE, "cbox-diffuse.usda")
    stage = author(base, z_up_cm=False)
    stage.Export(os.path.join(HERE, "cbox-diffuse.usdc"))
    usdz = os.path.join(HERE, "cbox-diffuse.usdz")
    if os.path.exists(usdz):
        os.remove(usdz)
    UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(os.path.join(HERE, "cbox-diffuse.usdc")), usdz)
    author(os.path.join(HERE, "cbox-diffuse-zup-cm.usda"), z_up_cm=True)

    quad = Usd.Stage.CreateNew(os.path.join(HERE, "quad.usda"))
    UsdGeom.SetStageUpAxis(quad, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(quad, 1.0)
    q = UsdGeom.Mesh.Define(quad, "/quad")
    q.CreatePointsAttr(Vt.Vec3fArray([(-0.1, 0, -0.1), (0.1, 0, -0.1), (0.1, 0, 0.1), (-0.1, 0, 0.1)]))
    q.CreateFaceVertexCountsAttr(Vt.IntArray([4]))
    q.CreateFaceVertexIndicesAttr(Vt.IntArray([0, 3, 2, 1]))
    quad.SetDefaultPrim(q.GetPrim())
    quad.GetRootLayer().Save()

    composed = Usd.Stage.CreateNew(os.path.join(HERE, "composed.usda"))
    composed.GetRootLayer().subLayerPaths.append("cbox-diffuse.usda")
    UsdGeom.SetStageUpAxis(composed, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(composed, 1.0)
    # Typeless here, so that the reference's Mesh type composes.
    extra = composed.DefinePrim("/cbox/extra")
    extra.GetReferences().AddReference("quad.usda", "/quad")
    UsdGeom.Xformable(extra).AddTranslateOp().Set(Gf.Vec3d(0.25, -0.5, 0.0))
    composed.GetRootLayer().Save()

    animated = Usd.Stage.CreateNew(os.path.join(HERE, "animated.usda"))
    UsdGeom.SetStageUpAxis(animated, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(animated, 1.0)
    animated.SetStartTimeCode(1)
    animated.SetEndTimeCode(10)
    moving = animated.DefinePrim("/moving")
    moving.GetReferences().AddReference("quad.usda", "/quad")
    op = UsdGeom.Xformable(moving).AddTranslateOp()
    op.Set(Gf.Vec3d(0, 0, 0), 1)
    op.Set(Gf.Vec3d(0.9, 0, 0), 10)
    animated.GetRootLayer().Save()

    from pxr import UsdLux
    lights = Usd.Stage.CreateNew(os.path.join(HERE, "lights.usda"))
    UsdGeom.SetStageUpAxis(lights, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(lights, 1.0)
    rect = UsdLux.RectLight.Define(lights, "/rect")
    rect.CreateWidthAttr(0.5)
    rect.CreateHeightAttr(0.25)
    rect.CreateIntensityAttr(10.0)
    rect.CreateExposureAttr(1.0)
    rect.CreateColorAttr(Gf.Vec3f(1.0, 0.5, 0.25))
    rect.AddTranslateOp().Set(Gf.Vec3d(0, 1, 0))
    rect.AddRotateXOp().Set(-90.0)  # local -Z (the emitting side) along world -Y
    disk = UsdLux.DiskLight.Define(lights, "/disk")
    disk.CreateRadiusAttr(0.1)
    disk.CreateIntensityAttr(3.0)
    disk.CreateNormalizeAttr(True)
    disk.AddTranslateOp().Set(Gf.Vec3d(-1, 0, 0))
    sphere = UsdLux.SphereLight.Define(lights, "/sphere")
    sphere.CreateRadiusAttr(0.2)
    sphere.CreateIntensityAttr(5.0)
    sphere.AddTranslateOp().Set(Gf.Vec3d(1, 0, 0))
    sun = UsdLux.DistantLight.Define(lights, "/sun")
    sun.CreateIntensityAttr(50000.0)
    sun.CreateAngleAttr(0.53)
    sun.AddRotateXOp().Set(-90.0)
    lights.GetRootLayer().Save()

    inst = Usd.Stage.CreateNew(os.path.join(HERE, "instancing.usda"))
    UsdGeom.SetStageUpAxis(inst, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(inst, 1.0)
    # A class holding the quad as a child, instanced twice: the quads are instance proxies.
    proto = inst.CreateClassPrim("/proto")
    inst.DefinePrim("/proto/quad").GetReferences().AddReference("quad.usda", "/quad")
    for i, x in enumerate([-0.5, 0.5]):
        prim = inst.DefinePrim(f"/instance{i}")
        prim.GetReferences().AddInternalReference(proto.GetPath())
        prim.SetInstanceable(True)
        UsdGeom.Xformable(prim).AddTranslateOp().Set(Gf.Vec3d(x, 0, 0))
    guide = UsdGeom.Mesh.Define(inst, "/guide")
    guide.GetPrim().GetReferences().AddReference("quad.usda", "/quad")
    guide.CreatePurposeAttr(UsdGeom.Tokens.guide)
    hidden = UsdGeom.Mesh.Define(inst, "/hidden")
    hidden.GetPrim().GetReferences().AddReference("quad.usda", "/quad")
    hidden.CreateVisibilityAttr(UsdGeom.Tokens.invisible)
    inst.GetRootLayer().Save()

    textured(os.path.join(HERE, "textured.usda"))
    roughness_test_lit(os.path.join(HERE, "roughness-test-lit.usda"))
    dome(os.path.join(HERE, "dome.usda"))
    dome_sky(os.path.join(HERE, "dome-sky.usda"), flipped=False)
    dome_sky(os.path.join(HERE, "dome-sky-flipped.usda"), flipped=True)

    # A usdz whose layer references a member that is not in the archive.
    layer = os.path.join(HERE, "missing-member-root.usda")
    with open(layer, "w") as f:
        f.write('#usda 1.0\ndef "a" (\n  references = @gone.usda@</x>\n)\n{\n}\n')
    usdz = os.path.join(HERE, "missing-member.usdz")
    if os.path.exists(usdz):
        os.remove(usdz)
    UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(layer), usdz)
    os.remove(layer)


def write_png(path, width, height, rgb):
    """An 8-bit RGB PNG (usd-core writes no images)."""
    import zlib

    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)

    rows = b"".join(b"\x00" + bytes(rgb[y * width * 3:(y + 1) * width * 3]) for y in range(height))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(rows)))
        f.write(chunk(b"IEND", b""))


def textured(path):
    # Rows top to bottom: (255, 0, 0) (0, 255, 0) / (0, 0, 255) (255, 255, 255).
    write_png(os.path.join(HERE, "checker.png"), 2, 2,
              [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255])
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    mesh = UsdGeom.Mesh.Define(stage, "/quad")
    mesh.CreatePointsAttr(Vt.Vec3fArray([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray([4]))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray([0, 1, 2, 3]))
    uv = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "uv", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.faceVarying)
    # Indexed: corners 0..3 take values 2, 0, 1, 3 of this table.
    uv.Set(Vt.Vec2fArray([(1, 0), (0, 1), (0, 0), (1, 1)]))
    uv.SetIndices(Vt.IntArray([2, 0, 3, 1]))
    material = UsdShade.Material.Define(stage, "/look")
    surface = UsdShade.Shader.Define(stage, "/look/surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    surface.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(1.0)
    reader = UsdShade.Shader.Define(stage, "/look/reader")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.Token).Set("uv")
    reader.CreateOutput("result", Sdf.ValueTypeNames.Float2)
    xf = UsdShade.Shader.Define(stage, "/look/transform")
    xf.CreateIdAttr("UsdTransform2d")
    xf.CreateInput("in", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.GetOutput("result"))
    xf.CreateInput("scale", Sdf.ValueTypeNames.Float2).Set(Gf.Vec2f(2, 2))
    xf.CreateInput("rotation", Sdf.ValueTypeNames.Float).Set(90.0)
    xf.CreateInput("translation", Sdf.ValueTypeNames.Float2).Set(Gf.Vec2f(1, 0))
    xf.CreateOutput("result", Sdf.ValueTypeNames.Float2)

    def texture(name, colour_space, wrap):
        tex = UsdShade.Shader.Define(stage, "/look/" + name)
        tex.CreateIdAttr("UsdUVTexture")
        tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("checker.png")
        tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set(colour_space)
        tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set(wrap)
        tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set(wrap)
        tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(xf.GetOutput("result"))
        return tex

    colour = texture("colour", "sRGB", "clamp")
    surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(
        colour.CreateOutput("rgb", Sdf.ValueTypeNames.Float3))
    rough = texture("rough", "raw", "clamp")
    rough.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(0.5, 0.5, 0.5, 1))
    rough.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(0.1, 0.1, 0.1, 0))
    surface.CreateInput("roughness", Sdf.ValueTypeNames.Float).ConnectToSource(
        rough.CreateOutput("g", Sdf.ValueTypeNames.Float))
    glow = texture("glow", "sRGB", "black")
    surface.CreateInput("emissiveColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(
        glow.CreateOutput("rgb", Sdf.ValueTypeNames.Float3))
    material.CreateSurfaceOutput().ConnectToSource(surface.CreateOutput("surface", Sdf.ValueTypeNames.Token))
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    stage.GetRootLayer().Save()


def roughness_test_lit(path):
    from pxr import UsdLux
    stage = Usd.Stage.CreateNew(path)
    # The referenced layer's stage metadata does not cross the reference: say it again.
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.DefinePrim("/Roughness").GetReferences().AddReference("roughness-test/RoughnessTest.usdz")
    # The cards span x -6.7 … 6.6, z 0 … 5.3 and face -y.
    light = UsdLux.RectLight.Define(stage, "/light")
    light.CreateWidthAttr(4.0)
    light.CreateHeightAttr(2.0)
    light.CreateIntensityAttr(20.0)
    light.AddTranslateOp().Set(Gf.Vec3d(0, -9, 4.5))
    light.AddRotateXOp().Set(90.0)  # local -Z (the emitting side) along world +y
    camera = UsdGeom.Camera.Define(stage, "/camera")
    camera.CreateFocalLengthAttr(24.0)
    camera.CreateVerticalApertureAttr(15.2908)
    camera.CreateHorizontalApertureAttr(20.955)
    camera.AddTranslateOp().Set(Gf.Vec3d(0, -16, 2.65))
    camera.AddRotateXOp().Set(90.0)  # looking along +y, z up
    stage.GetRootLayer().Save()


def diffuse_material(stage, path, albedo):
    material = UsdShade.Material.Define(stage, path)
    surface = UsdShade.Shader.Define(stage, path + "/surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(albedo))
    surface.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(1.0)
    material.CreateSurfaceOutput().ConnectToSource(surface.CreateOutput("surface", Sdf.ValueTypeNames.Token))
    return material


def dome(path):
    from pxr import UsdLux
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    rings, segments = 24, 48
    points, normals, counts, indices = [(0, 1, 0)], [(0, 1, 0)], [], []
    for i in range(1, rings):
        theta = math.pi * i / rings
        for k in range(segments):
            phi = 2 * math.pi * k / segments
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            points.append(n)
            normals.append(n)
    points.append((0, -1, 0))
    normals.append((0, -1, 0))
    at = lambda i, k: 1 + (i - 1) * segments + k % segments
    south = len(points) - 1
    for k in range(segments):
        counts += [3, 3]
        indices += [0, at(1, k), at(1, k + 1)]
        indices += [south, at(rings - 1, k + 1), at(rings - 1, k)]
    for i in range(1, rings - 1):
        for k in range(segments):
            counts.append(4)
            indices += [at(i, k), at(i + 1, k), at(i + 1, k + 1), at(i, k + 1)]
    sphere = UsdGeom.Mesh.Define(stage, "/sphere")
    sphere.CreatePointsAttr(Vt.Vec3fArray(points))
    sphere.CreateNormalsAttr(Vt.Vec3fArray(normals))
    sphere.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
    sphere.CreateFaceVertexCountsAttr(Vt.IntArray(counts))
    sphere.CreateFaceVertexIndicesAttr(Vt.IntArray(indices))
    UsdShade.MaterialBindingAPI.Apply(sphere.GetPrim()).Bind(diffuse_material(stage, "/grey", (0.5, 0.5, 0.5)))
    light = UsdLux.DomeLight.Define(stage, "/dome")
    light.CreateColorAttr(Gf.Vec3f(0.5, 0.5, 0.5))
    light.CreateIntensityAttr(2.0)
    camera = UsdGeom.Camera.Define(stage, "/camera")
    camera.CreateFocalLengthAttr(50.0)
    camera.CreateVerticalApertureAttr(24.0)
    camera.AddTranslateOp().Set(Gf.Vec3d(0, 0, 5))
    stage.GetRootLayer().Save()


def dome_sky(path, flipped):
    from pxr import UsdLux
    width, height = 64, 32
    if not flipped:
        write_png(os.path.join(HERE, "sky.png"), width, height,
                  [255 if y < height // 2 else 0 for y in range(height) for _ in range(width * 3)])
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    floor = UsdGeom.Mesh.Define(stage, "/floor")
    floor.CreatePointsAttr(Vt.Vec3fArray([(-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1)]))
    floor.CreateFaceVertexCountsAttr(Vt.IntArray([4]))
    floor.CreateFaceVertexIndicesAttr(Vt.IntArray([0, 1, 2, 3]))
    UsdShade.MaterialBindingAPI.Apply(floor.GetPrim()).Bind(diffuse_material(stage, "/grey", (0.5, 0.5, 0.5)))
    light = UsdLux.DomeLight.Define(stage, "/sky")
    light.CreateTextureFileAttr("sky.png")
    light.CreateTextureFormatAttr(UsdLux.Tokens.latlong)
    if flipped:
        light.AddRotateXOp().Set(180.0)
    camera = UsdGeom.Camera.Define(stage, "/camera")
    camera.CreateFocalLengthAttr(50.0)
    camera.CreateVerticalApertureAttr(24.0)
    camera.AddTranslateOp().Set(Gf.Vec3d(0, 3, 0))
    camera.AddRotateXOp().Set(-90.0)  # looking down
    stage.GetRootLayer().Save()


if __name__ == "__main__":
    main()
