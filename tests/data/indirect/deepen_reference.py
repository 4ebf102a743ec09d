"""Deepen a `mitsuba_ref.py ... 64 4096 --var` reference (16 batches of 256 spp, seeds 0-15).

usage: python deepen_reference.py SCENE.gltf REF.exr VAR.exr NB OUT_REF.exr OUT_VAR.exr

Renders NB more batches of 256 spp (Mitsuba 3 `llvm_ad_rgb`, `path` max_depth 64, 256², seeds
1000..1000+NB-1, the scene converted by the anchor's `gltf2mi.py` as `mitsuba_ref.py` does) and
writes the mean of all 16 + NB batches and the pooled per-sample variance (the variance of an
M-spp render is about VAR/M). The indirect-lit scenes' references are 4 096 + 48 x 256 =
16 384 spp: at 4 096 their pixels' own noise was 18 % (median), which inflated a relMSE whose
denominator is the reference (docs/testing.md)."""
import os, sys, time
os.environ.setdefault('DRJIT_LIBLLVM_PATH', '/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1')
import numpy as np, mitsuba as mi
mi.set_variant('llvm_ad_rgb')
sys.path.insert(0, os.environ.get('MITSUBA_ANCHOR', os.path.join(os.path.dirname(os.path.abspath(__file__)), '../../../../shared/tools/mitsuba_anchor')))
import gltf2mi
scene_path, ref0, var0, nb, out, outvar = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5], sys.argv[6]
d, _ = gltf2mi.scene_dict(scene_path, '/tmp/deepen-ply/' + os.path.basename(scene_path), 64, res=256)
scene = mi.load_dict(d, optimize=False)
n = 256
s1 = np.zeros((256, 256, 3)); s2 = np.zeros_like(s1)
t = time.time()
for b in range(nb):
    m = np.array(mi.render(scene, spp=n, seed=1000 + b), dtype=np.float64)[..., :3]
    s1 += m; s2 += m * m
    print(f'batch {b+1}/{nb} {time.time()-t:.0f}s', flush=True)
load = lambda p: np.array(mi.Bitmap(p), dtype=np.float64)[..., :3]
m0 = load(ref0); v0 = load(var0)
m1 = s1 / nb; v1 = np.maximum(s2 - nb * m1 * m1, 0) / (nb - 1) * n
mean = (16 * m0 + nb * m1) / (16 + nb)
var = (15 * v0 + (nb - 1) * v1) / (15 + nb - 1)
w = lambda p, a: mi.Bitmap(np.ascontiguousarray(a, dtype=np.float32), mi.Bitmap.PixelFormat.RGB).write(p)
w(out, mean); w(outvar, var)
print('spp', 256 * (16 + nb))
