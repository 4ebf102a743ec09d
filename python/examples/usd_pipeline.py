"""Bake a USD stage with wpbgi and record the cache on the stage, so that downstream tools find
it and later runs re-use it while it is still good. Needs Pixar's USD Python modules
(`pip install usd-core`) and the wpbgi package (`pip install ./python`).

    python3 python/examples/usd_pipeline.py STAGE.usda|.usdc [--cache PATH] [--quality Q]
                                            [--points N] [--bounces N|auto] [--seed S]

Settings not given are the library's defaults, those of `wpbgi bake`.

The root layer's customLayerData gets a `wpbgi` dictionary:

    customLayerData = {
        dictionary wpbgi = {
            string cache = "STAGE.wpc"     # relative to the layer, as asset paths are
            string hash = "0123…"          # the bake's content hash (wpbgi inspect prints it)
            string version = "0.1.0"       # the wpbgi that baked it
        }
    }

A later run bakes nothing when the recorded hash is the hash a bake of the stage would have
now (the same geometry, materials, textures, lights, settings and wpbgi version; the record
itself and cameras do not count) and the recorded file is a cache with that hash. Otherwise it
bakes, writes the cache atomically, and updates the record. It prints one JSON line:
{"stage": …, "cache": …, "hash": …, "baked": true|false, "reason": …}.
"""

import argparse
import json
import os
import sys

try:
    from pxr import Sdf
except ImportError:
    Sdf = None

import wpbgi

KEY = "wpbgi"


def recorded(layer):
    """The wpbgi record of the layer, or {}."""
    return dict(layer.customLayerData.get(KEY, {}))


def record(layer, cache_rel, hash_):
    data = dict(layer.customLayerData)
    data[KEY] = {"cache": cache_rel, "hash": hash_, "version": wpbgi.__version__}
    layer.customLayerData = data
    if not layer.Save():
        raise RuntimeError(f"{layer.identifier}: cannot save the layer")


def cache_hash(path, scene):
    """The hash of the cache at `path` if it is a good cache of `scene`, else None."""
    if not os.path.exists(path):
        return None
    try:
        return wpbgi.Cache(scene, path).hash
    except wpbgi.Error:
        return None


def run(stage_path, cache=None, progress=None, **settings):
    """Make sure the stage has a good cache; return what was done (the printed JSON)."""
    if Sdf is None:
        raise RuntimeError("Pixar's USD Python modules are not installed (pip install usd-core)")
    if stage_path.lower().endswith(".usdz"):
        raise RuntimeError(f"{stage_path}: a usdz package cannot be changed; record on a stage that references it")
    layer = Sdf.Layer.FindOrOpen(stage_path)
    if layer is None:
        raise RuntimeError(f"{stage_path}: cannot open the layer")
    folder = os.path.dirname(os.path.abspath(stage_path))
    rec = recorded(layer)
    cache_rel = cache or rec.get("cache") or os.path.splitext(os.path.basename(stage_path))[0] + ".wpc"
    cache_path = cache_rel if os.path.isabs(cache_rel) else os.path.join(folder, cache_rel)
    scene = wpbgi.Scene(stage_path)
    want = wpbgi.bake_hash(scene, **settings)
    have = cache_hash(cache_path, scene)
    if rec.get("hash") == want and have == want:
        return {"stage": stage_path, "cache": cache_path, "hash": want, "baked": False,
                "reason": "the recorded cache is still good"}
    if rec.get("hash") != want:
        reason = "no record" if not rec else "the stage or the settings changed"
    else:
        reason = "the recorded cache is missing or stale"
    wpbgi.bake(scene, cache_path, progress=progress, **settings)
    record(layer, cache_rel, want)
    return {"stage": stage_path, "cache": cache_path, "hash": want, "baked": True, "reason": reason}


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("stage")
    p.add_argument("--cache", help="where the cache goes (default: the record's, or STAGE.wpc)")
    p.add_argument("--quality", help="draft, preview, final or ultra (default: wpbgi bake's)")
    p.add_argument("--points", type=int, help="surfels (default: the preset's)")
    p.add_argument("--bounces", help="indirect bounces, or auto (default: wpbgi bake's)")
    p.add_argument("--seed", type=int)
    a = p.parse_args(argv[1:])
    bounces = a.bounces if a.bounces in (None, "auto") else int(a.bounces)

    def progress(stage, fraction):
        print(f"\r  {stage:<14} {100 * fraction:3.0f}%", end="", file=sys.stderr)

    try:
        result = run(a.stage, a.cache, progress, quality=a.quality, points=a.points,
                     bounces=bounces, seed=a.seed)
    except (wpbgi.Error, RuntimeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    if result["baked"]:
        print(file=sys.stderr)
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
