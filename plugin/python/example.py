"""Bake a scene and render it from the cache with wpbgi's Python binding (ctypes).

    python3 plugin/python/example.py SCENE CACHE OUT.pfm [POINTS [BOUNCES [SIZE]]]

The same arguments and the same image as plugin/examples/bake_and_render.c.
"""

import sys
import time

import wpbgi


def main(argv):
    if len(argv) < 4:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    scene_path, cache_path, out_path = argv[1:4]
    points = int(argv[4]) if len(argv) > 4 else 0
    bounces = int(argv[5]) if len(argv) > 5 else "auto"
    size = int(argv[6]) if len(argv) > 6 else 128
    try:
        with wpbgi.Scene(scene_path) as scene:
            start = time.monotonic()
            wpbgi.bake(scene, cache_path, points=points, bounces=bounces,
                       progress=lambda stage, f: print(f"\r  {stage:<14} {100 * f:3.0f}%",
                                                       end="", file=sys.stderr))
            print(f"\n  baked {cache_path} in {time.monotonic() - start:.2f} s", file=sys.stderr)
            with wpbgi.Cache(cache_path, scene) as cache:
                rgb = wpbgi.render(scene, cache, size, size)
                wpbgi.write_pfm(out_path, rgb, size, size)
                print(f"  wrote {out_path} ({size}x{size}, cache {cache.hash})", file=sys.stderr)
    except wpbgi.Error as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
