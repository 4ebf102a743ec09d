"""wpbgi: noise-free global illumination for glTF and USD scenes, from Python.

Bake a scene's light into a cache once, then render numpy images from it::

    import wpbgi

    scene = wpbgi.Scene("scene.usdc")                       # or .gltf, .glb, .usda, .usdz
    report = wpbgi.bake(scene, "scene.wpc", progress=lambda stage, f: print(stage, f))
    cache = wpbgi.Cache(scene, "scene.wpc")                 # refused if the scene changed
    image = wpbgi.render(scene, cache, 512, 512)            # numpy float32, shape (512, 512, 3)

Settings are keyword arguments named as the library's fields: for ``bake``, ``quality``
("draft", "preview", "final", "ultra"), ``points``, ``light_samples``, ``threshold``,
``split_level``, ``seed``, ``max_cut``, ``bounces`` ("auto" or a number), ``receiver_stride``,
``transport_memory`` (MB), ``surfel_density`` ({material: factor}); for ``render``, ``gather``
("fpbgi", "pbgi", "paths"), ``mb_size``, ``adaptive``, ``glossy_below``, ``adaptive_share``,
``adaptive_levels``, ``light_samples``, ``specular_below``, ``chain_depth``, ``max_depth``,
``clusters``, ``far_eps``, ``spp``, ``sparse``, ``seed``. What is not given keeps the default of
the ``wpbgi`` command; a value out of range raises ``wpbgi.Error`` naming it.

Lights and materials change after the bake through edits in the syntax of ``wpbgi --set``::

    warm = ["key.emission*=1.2,1,0.8"]
    wpbgi.relight(scene, "scene.wpc", "warm.wpc", warm)     # rescaled, or baked again
    image = wpbgi.render(scene.edited(warm), wpbgi.Cache(scene.edited(warm), "warm.wpc"))

``progress(stage, fraction)`` is called on the calling thread; returning True (or raising, or
Ctrl-C) cancels the work, which raises ``wpbgi.Cancelled`` (or what the callback raised).
``threads`` picks the worker count (0: one per core); the results do not depend on it.
"""

import numpy

from . import _native
from ._native import Cache, Cancelled, Error, Scene, __version__, bake, bake_hash, relight

__all__ = ["Scene", "Cache", "bake", "bake_hash", "render", "relight", "Error", "Cancelled", "__version__"]


def render(scene, cache, width=None, height=None, camera=None, *, threads=0, progress=None, **settings):
    """The final render of `scene` from `cache`: linear RGB, numpy float32 of shape
    (height, width, 3), rows top first. The size defaults as for ``wpbgi render`` (the scene's
    render settings, else the library's default size); `camera` names a scene camera (None: its first, or one
    that frames the scene). The floats are those ``wpbgi render`` writes to its EXR."""
    data, h, w = _native.render(
        scene, cache, width, height, camera, threads=threads, progress=progress, **settings
    )
    return numpy.frombuffer(bytearray(data), dtype="<f4").reshape(h, w, 3)
