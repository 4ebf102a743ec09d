"""wpbgi from Python through its C ABI, with ctypes: nothing to build.

The library is found through the WPBGI_LIBRARY environment variable (the path of
libwpbgi_plugin.so / .dylib / wpbgi_plugin.dll), else in the repository's target/release
and target/debug folders, else on the system's library path.

    import wpbgi
    scene = wpbgi.Scene("scene.gltf")
    wpbgi.bake(scene, "scene.wpc", points=20000, progress=lambda stage, f: print(stage, f))
    cache = wpbgi.Cache("scene.wpc", scene)
    rgb = wpbgi.render(scene, cache, 256, 256)   # array('f'): width * height * 3, rows top first

Every failure raises wpbgi.Error, whose message names the file and object at fault.
"""

import array
import ctypes
import ctypes.util
import os
import sys
from pathlib import Path

ABI_VERSION = 1

OK = 0
INVALID_ARGUMENT = 1
FAILED = 2
CANCELLED = 3
INTERNAL_ERROR = 4

QUALITIES = {"draft": 0, "preview": 1, "final": 2, "ultra": 3}


class Error(Exception):
    """A call into wpbgi failed; `status` is its code (INVALID_ARGUMENT, FAILED, ...)."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


class Cancelled(Error):
    """The progress callback asked the bake to stop; nothing was written."""


class _BakeSettings(ctypes.Structure):
    _fields_ = [
        ("struct_size", ctypes.c_uint32),
        ("quality", ctypes.c_uint32),
        ("points", ctypes.c_uint64),
        ("light_samples", ctypes.c_uint32),
        ("bounces", ctypes.c_int32),
        ("seed", ctypes.c_uint64),
        ("threads", ctypes.c_uint32),
    ]


class _RenderSettings(ctypes.Structure):
    _fields_ = [
        ("struct_size", ctypes.c_uint32),
        ("width", ctypes.c_uint32),
        ("height", ctypes.c_uint32),
        ("light_samples", ctypes.c_uint32),
        ("camera", ctypes.c_char_p),
        ("seed", ctypes.c_uint64),
        ("threads", ctypes.c_uint32),
    ]


_PROGRESS = ctypes.CFUNCTYPE(ctypes.c_int32, ctypes.c_char_p, ctypes.c_float, ctypes.c_void_p)
_HANDLE = ctypes.c_void_p


def _library_candidates():
    env = os.environ.get("WPBGI_LIBRARY")
    if env:
        yield env
        return
    names = {"linux": "libwpbgi_plugin.so", "darwin": "libwpbgi_plugin.dylib"}
    name = names.get(sys.platform, "wpbgi_plugin.dll")
    root = Path(__file__).resolve().parents[2]
    for profile in ("release", "debug"):
        yield str(root / "target" / profile / name)
    found = ctypes.util.find_library("wpbgi_plugin")
    if found:
        yield found


def _load():
    tried = []
    for path in _library_candidates():
        if os.path.exists(path) or not os.path.dirname(path):
            try:
                lib = ctypes.CDLL(path)
                break
            except OSError as e:
                tried.append(f"{path} ({e})")
        else:
            tried.append(f"{path} (missing)")
    else:
        raise ImportError(
            "cannot find the wpbgi library: build it with `cargo build --release -p wpbgi-plugin` "
            "or set WPBGI_LIBRARY; tried " + ", ".join(tried)
        )
    lib.wpbgi_abi_version.restype = ctypes.c_uint32
    if lib.wpbgi_abi_version() != ABI_VERSION:
        raise ImportError(
            f"{path} is wpbgi ABI {lib.wpbgi_abi_version()}, but this module speaks ABI {ABI_VERSION}"
        )
    signatures = {
        "wpbgi_version": ([], ctypes.c_char_p),
        "wpbgi_last_error": ([], ctypes.c_char_p),
        "wpbgi_bake_settings_init": ([ctypes.POINTER(_BakeSettings)], ctypes.c_int32),
        "wpbgi_render_settings_init": ([ctypes.POINTER(_RenderSettings)], ctypes.c_int32),
        "wpbgi_scene_load": ([ctypes.c_char_p, ctypes.POINTER(_HANDLE)], ctypes.c_int32),
        "wpbgi_scene_set_environment": (
            [_HANDLE, ctypes.c_char_p, ctypes.c_float, ctypes.c_float],
            ctypes.c_int32,
        ),
        "wpbgi_scene_load_at": (
            [ctypes.c_char_p, ctypes.c_double, ctypes.POINTER(_HANDLE)],
            ctypes.c_int32,
        ),
        "wpbgi_scene_edit": ([_HANDLE, ctypes.c_char_p], ctypes.c_int32),
        "wpbgi_scene_free": ([_HANDLE], None),
        "wpbgi_cache_open": ([_HANDLE, ctypes.c_char_p, ctypes.POINTER(_HANDLE)], ctypes.c_int32),
        "wpbgi_cache_hash": ([_HANDLE, ctypes.c_char_p, ctypes.c_size_t], ctypes.c_int32),
        "wpbgi_cache_free": ([_HANDLE], None),
        "wpbgi_bake": (
            [_HANDLE, ctypes.POINTER(_BakeSettings), ctypes.c_char_p, _PROGRESS, ctypes.c_void_p],
            ctypes.c_int32,
        ),
        "wpbgi_relight": (
            [_HANDLE, _HANDLE, ctypes.POINTER(ctypes.c_char_p), ctypes.c_size_t, ctypes.c_char_p,
             ctypes.c_uint32, _PROGRESS, ctypes.c_void_p, ctypes.POINTER(ctypes.c_int32)],
            ctypes.c_int32,
        ),
        "wpbgi_bake_hash": (
            [_HANDLE, ctypes.POINTER(_BakeSettings), ctypes.c_char_p, ctypes.c_size_t],
            ctypes.c_int32,
        ),
        "wpbgi_render": (
            [_HANDLE, _HANDLE, ctypes.POINTER(_RenderSettings), ctypes.POINTER(ctypes.c_float), ctypes.c_size_t],
            ctypes.c_int32,
        ),
        "wpbgi_render_to_file": (
            [_HANDLE, _HANDLE, ctypes.POINTER(_RenderSettings), ctypes.c_char_p],
            ctypes.c_int32,
        ),
        "wpbgi_preview": (
            [_HANDLE, _HANDLE, ctypes.POINTER(_RenderSettings), ctypes.POINTER(ctypes.c_float), ctypes.c_size_t],
            ctypes.c_int32,
        ),
    }
    for name, (args, result) in signatures.items():
        f = getattr(lib, name)
        f.argtypes = args
        f.restype = result
    return lib


_lib = _load()


def version():
    """The library's version, e.g. "0.1.0"."""
    return _lib.wpbgi_version().decode()


def _check(status):
    if status != OK:
        message = _lib.wpbgi_last_error().decode(errors="replace")
        raise (Cancelled if status == CANCELLED else Error)(status, message)


def _path(p):
    return os.fsencode(os.fspath(p))


class _Handle:
    """A library handle, freed by `close()`, at the end of a `with` block, or when collected."""

    _handle = _HANDLE()
    _free = None

    def close(self):
        if self._handle:
            type(self)._free(self._handle)
            self._handle = _HANDLE()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()


class Scene(_Handle):
    """A glTF or USD scene, loaded (a USD stage at `time_code`, a frame, when given)."""

    _free = _lib.wpbgi_scene_free

    def __init__(self, path, time_code=None):
        handle = _HANDLE()
        if time_code is None:
            _check(_lib.wpbgi_scene_load(_path(path), ctypes.byref(handle)))
        else:
            _check(
                _lib.wpbgi_scene_load_at(
                    _path(path), float(time_code), ctypes.byref(handle)
                )
            )
        self._handle = handle
        self.path = os.fspath(path)

    def set_environment(self, spec, intensity=1.0, rotate_degrees=0.0):
        """Light the scene with an environment, as the command line's --env: "R,G,B", "V", or
        the path of a latitude-longitude .exr or .hdr image."""
        _check(
            _lib.wpbgi_scene_set_environment(
                self._handle,
                os.fsencode(spec),
                float(intensity),
                float(rotate_degrees),
            )
        )

    def edit(self, edit):
        """Edit the scene as the command line's --set: "NAME.PARAMETER=VALUE" or
        "NAME.PARAMETER*=VALUE". The edit is part of the scene, so of the bake's hash."""
        _check(_lib.wpbgi_scene_edit(self._handle, edit.encode()))


class Cache(_Handle):
    """A baked cache. With a scene, it is refused unless it was baked from that scene as it is."""

    _free = _lib.wpbgi_cache_free

    def __init__(self, path, scene=None):
        handle = _HANDLE()
        _check(_lib.wpbgi_cache_open(scene._handle if scene else None, _path(path), ctypes.byref(handle)))
        self._handle = handle
        self.path = os.fspath(path)

    @property
    def hash(self):
        """The content hash it was baked with (32 hexadecimal digits)."""
        out = ctypes.create_string_buffer(33)
        _check(_lib.wpbgi_cache_hash(self._handle, out, len(out)))
        return out.value.decode()


def _bake_settings(quality, points, light_samples, bounces, seed, threads):
    """The library's bake defaults (wpbgi_bake_settings_init), with what is not None set."""
    s = _BakeSettings()
    _check(_lib.wpbgi_bake_settings_init(ctypes.byref(s)))
    if quality is not None:
        if quality not in QUALITIES:
            raise Error(INVALID_ARGUMENT, f"quality must be one of {', '.join(QUALITIES)}, got {quality!r}")
        s.quality = QUALITIES[quality]
    s.points = points
    s.light_samples = light_samples
    if bounces is not None:
        s.bounces = -1 if bounces == "auto" else bounces
    if seed is not None:
        s.seed = seed
    s.threads = threads
    return s


def bake_hash(scene, quality=None, points=0, light_samples=0, bounces=None, seed=None):
    """The content hash a bake with these settings would have (equal to Cache.hash of its cache)."""
    s = _bake_settings(quality, points, light_samples, bounces, seed, 0)
    out = ctypes.create_string_buffer(33)
    _check(_lib.wpbgi_bake_hash(scene._handle, ctypes.byref(s), out, len(out)))
    return out.value.decode()


def bake(scene, cache_path, quality=None, points=0, light_samples=0, bounces=None, seed=None,
         threads=0, progress=None):
    """Bake `scene` to `cache_path` (atomically). `progress(stage, fraction)` is called on this
    thread; if it returns True the bake stops and Cancelled is raised. None means the library's
    default (that of `wpbgi bake`: the preview preset, automatic bounces); 0 means the preset's
    value for points and light_samples, and one thread per core for threads."""
    s = _bake_settings(quality, points, light_samples, bounces, seed, threads)
    _reporting(progress, lambda callback: _lib.wpbgi_bake(
        scene._handle, ctypes.byref(s), _path(cache_path), callback, None))


def relight(scene, cache, edits, output, threads=0, progress=None):
    """Relight `cache` (a fresh bake of `scene`) for `scene` with `edits` applied (each as
    Scene.edit takes it) and write the new cache to `output`. Returns True where the cache was
    rescaled (every emitter changed by one factor), False where the edited scene was baked
    again. The new cache opens for a scene given the same edits."""
    texts = (ctypes.c_char_p * len(edits))(*[e.encode() for e in edits])
    rescaled = ctypes.c_int32(-1)
    _reporting(progress, lambda callback: _lib.wpbgi_relight(
        scene._handle, cache._handle, texts, len(edits), _path(output), threads, callback, None,
        ctypes.byref(rescaled)))
    return rescaled.value == 1


def _reporting(progress, call):
    """Run `call(callback)`, `callback` passing the library's reports to `progress(stage,
    fraction)` on this thread: True stops the work (Cancelled is raised), and an exception it
    raises stops the work and is raised here after the call returns."""
    failure = []

    def report(stage, fraction, _user):
        try:
            return 1 if progress(stage.decode(), fraction) else 0
        except BaseException as e:
            failure.append(e)
            return 1

    status = call(_PROGRESS(report) if progress else _PROGRESS())
    if failure:
        raise failure[0]
    _check(status)


def _render_settings(width, height, camera, light_samples, seed, threads):
    s = _RenderSettings()
    _check(_lib.wpbgi_render_settings_init(ctypes.byref(s)))
    s.width, s.height = width, height
    s.camera = camera.encode() if camera else None
    if light_samples:
        s.light_samples = light_samples
    s.seed, s.threads = seed, threads
    return s


def render(scene, cache, width, height, camera=None, light_samples=0, seed=0, threads=0):
    """The final render: array('f') of width * height * 3 linear RGB floats, rows top first."""
    s = _render_settings(width, height, camera, light_samples, seed, threads)
    out = (ctypes.c_float * (width * height * 3))()
    _check(_lib.wpbgi_render(scene._handle, cache._handle, ctypes.byref(s), out, len(out)))
    return array.array("f", out)


def render_to_file(scene, cache, path, width, height, camera=None, light_samples=0, seed=0, threads=0):
    """The final render written to `path` (.exr: float; .png: sRGB 8-bit)."""
    s = _render_settings(width, height, camera, light_samples, seed, threads)
    _check(_lib.wpbgi_render_to_file(scene._handle, cache._handle, ctypes.byref(s), _path(path)))


def preview(cache, width, height, scene=None, camera=None):
    """The headless Vulkan preview, laid out as render()'s result."""
    s = _render_settings(width, height, camera, 0, 0, 0)
    out = (ctypes.c_float * (width * height * 3))()
    _check(_lib.wpbgi_preview(scene._handle if scene else None, cache._handle, ctypes.byref(s), out, len(out)))
    return array.array("f", out)


def write_pfm(path, rgb, width, height):
    """Write linear RGB floats (rows top first) as a little-endian Portable Float Map."""
    rows = [rgb[y * width * 3:(y + 1) * width * 3] for y in range(height)]
    with open(path, "wb") as f:
        f.write(f"PF\n{width} {height}\n-1.0\n".encode())
        for row in reversed(rows):
            data = array.array("f", row)
            if sys.byteorder == "big":
                data.byteswap()
            f.write(data.tobytes())
