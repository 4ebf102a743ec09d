"""A deep reference: Mitsuba's max_depth 8 reference plus the light of paths longer than 8.

usage: python deep_reference.py SCENE_GLTF REF_D8_EXR OUT_EXR [SPP] [DEPTH]
The tail (vertices 9..DEPTH, default 64) is rendered as Mitsuba's max_depth DEPTH image less
its max_depth 8 image with the same seeds (SPP samples a pixel in passes of 256, default 1024):
the two agree on every path up to the eighth vertex, so the difference holds the tail alone,
with the tail's small variance, and the d8 reference's own quality carries over. Prints the
tail's mean over the reference's, per channel. Needs what mitsuba_oidn.py needs.
Used in docs/render.md ("What stops cbox-rough") to judge renders against the light the scene
has beyond Mitsuba's depth-8 truncation."""
import os, sys
os.environ.setdefault('DRJIT_LIBLLVM_PATH', '/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1')
import numpy as np
import mitsuba as mi
mi.set_variant('llvm_ad_rgb')
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf2mi

scene_path, ref_path, out_path = sys.argv[1], sys.argv[2], sys.argv[3]
spp = int(sys.argv[4]) if len(sys.argv) > 4 else 1024
deep = int(sys.argv[5]) if len(sys.argv) > 5 else 64
ref = np.array(mi.Bitmap(ref_path), dtype=np.float64)[..., :3]
ply = os.path.join(os.environ.get('TMPDIR', '/tmp'), 'mitsuba-anchor-ply', os.path.basename(scene_path))
means = []
for depth in (8, deep):
    d, _ = gltf2mi.scene_dict(scene_path, ply, depth, res=ref.shape[0])
    scene = mi.load_dict(d, optimize=False)
    passes = max(1, spp // 256)
    acc = np.zeros_like(ref)
    for k in range(passes):
        acc += np.array(mi.render(scene, spp=256, seed=5000 + k), dtype=np.float64)[..., :3]
    means.append(acc / passes)
tail = means[1] - means[0]
print(os.path.basename(scene_path), 'tail mean / reference mean:', tail.mean(axis=(0, 1)) / ref.mean(axis=(0, 1)))
mi.util.write_bitmap(out_path, (ref + tail).astype(np.float32))
