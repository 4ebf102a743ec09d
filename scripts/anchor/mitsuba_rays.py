"""Ray queries alone: Mitsuba 3 llvm_ad_rgb (Embree) on the rays a wpbgi benchmark wrote.

usage: python mitsuba_rays.py SCENE_GLTF RAYS_FILE [ROUNDS]
RAYS_FILE: little-endian float32, ten per ray: origin (3), unit direction (3) of a closest-hit
query; unit direction (3) and length (1) of an occlusion segment from the same origin, tested
over (0, 0.999 length). Prints one JSON line: the wall seconds of each query over all the rays
(the fastest of ROUNDS after an untimed warm-up; the rays are made into Mitsuba arrays before
the timing, so it holds the tracing alone), how many closest-hit rays hit and how many segments
are occluded; then the same for the scene loaded with `embree_use_robust_intersections`
(Embree's RTC_SCENE_FLAG_ROBUST: its watertight triangle test and rounding-safe box test, as
wpbgi's accel always is; Mitsuba's default is off), as closest_robust_s, occluded_robust_s,
hits_robust and occluded_robust.
Needs: pip install mitsuba numpy; DRJIT_LIBLLVM_PATH set (libllvm19)."""
import json, os, sys, time
os.environ.setdefault('DRJIT_LIBLLVM_PATH', '/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1')
import numpy as np
import drjit as dr
import mitsuba as mi
mi.set_variant('llvm_ad_rgb')
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf2mi

scene_path, rays_path = sys.argv[1], sys.argv[2]
rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 5
rays = np.fromfile(rays_path, dtype='<f4').reshape(-1, 10)
d, _ = gltf2mi.scene_dict(scene_path, os.path.join(os.environ.get('TMPDIR', '/tmp'), 'mitsuba-anchor-ply', os.path.basename(scene_path)), 8, res=16)

def ray(origin, direction, maxt=None):
    r = mi.Ray3f(mi.Point3f(*[mi.Float(origin[:, i]) for i in range(3)]),
                 mi.Vector3f(*[mi.Float(direction[:, i]) for i in range(3)]))
    if maxt is not None:
        r.maxt = mi.Float(maxt)
    return r

closest = ray(rays[:, 0:3], rays[:, 3:6])
segment = ray(rays[:, 0:3], rays[:, 6:9], rays[:, 9] * np.float32(0.999))
dr.eval(closest, segment)
dr.sync_thread()

def timed(query):
    query()
    best, out = float('inf'), None
    for _ in range(rounds):
        t0 = time.perf_counter()
        out = query()
        dr.eval(out)
        dr.sync_thread()
        best = min(best, time.perf_counter() - t0)
    return best, np.array(out)

out = dict(scene=os.path.basename(scene_path), rays=len(rays))
for suffix, robust in [('', False), ('_robust', True)]:
    d['embree_use_robust_intersections'] = robust
    scene = mi.load_dict(d, optimize=False)
    t_closest, hit_t = timed(lambda: scene.ray_intersect_preliminary(closest).t)
    t_occluded, occluded = timed(lambda: scene.ray_test(segment))
    out.update({f'closest{suffix}_s': round(t_closest, 4), f'occluded{suffix}_s': round(t_occluded, 4),
                f'hits{suffix}': int(np.sum(np.isfinite(hit_t) & (hit_t < 1e30))),
                f'occluded{suffix}': int(np.sum(occluded))})
print(json.dumps(out), flush=True)
