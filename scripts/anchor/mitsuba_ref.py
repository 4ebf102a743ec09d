"""Render a Mitsuba 3 reference (its mean and per-sample variance) of a glTF scene.

usage: python mitsuba_ref.py SCENE_GLTF OUT.exr MAX_DEPTH SPP [--var OUT_VAR.exr] [--size N]
16 independent batches (seeds 0..15) of SPP/16 samples each, llvm_ad_rgb `path`; writes the mean and,
with --var, the per-sample variance estimated from the batches (the variance of an M-spp render is
about var/M). Same set-up as mitsuba_oidn.py."""
import argparse, os, sys
os.environ.setdefault('DRJIT_LIBLLVM_PATH', '/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1')
import numpy as np
import mitsuba as mi
mi.set_variant('llvm_ad_rgb')
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf2mi

a = argparse.ArgumentParser()
a.add_argument('scene'); a.add_argument('out'); a.add_argument('depth', type=int); a.add_argument('spp', type=int)
a.add_argument('--var'); a.add_argument('--size', type=int, default=256)
o = a.parse_args()
d, _ = gltf2mi.scene_dict(o.scene, os.path.join(os.environ.get('TMPDIR', '/tmp'), 'mitsuba-anchor-ply',
                                                 os.path.basename(o.scene)), o.depth, res=o.size)
scene = mi.load_dict(d, optimize=False)
n = max(1, o.spp // 16)
s1 = np.zeros((o.size, o.size, 3)); s2 = np.zeros_like(s1)
for b in range(16):
    m = np.array(mi.render(scene, spp=n, seed=b), dtype=np.float64)[..., :3]
    s1 += m; s2 += m * m
    print(f'batch {b + 1}/16', flush=True)
mean = s1 / 16
def write(path, img):
    mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32), mi.Bitmap.PixelFormat.RGB).write(path)
write(o.out, mean)
# The sample count beside the image (`caustic_d64_ref.exr` → `caustic_d64_ref.spp`), for
# whoever takes its noise out of an error (examples/bench_still.rs).
with open(os.path.splitext(o.out)[0] + '.spp', 'w') as f:
    f.write(f'{n * 16}\n')
if o.var:
    write(o.var, np.maximum(s2 - 16 * mean * mean, 0) / 15 * n)
