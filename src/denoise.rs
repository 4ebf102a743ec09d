//! Intel Open Image Denoise for the path-traced modes (`render --denoise`): the `RT` filter on
//! an HDR image, guided by the albedo and normal of the first hit, as a user would run it. The
//! render hands it the indirect light only and adds emission and direct light back (see
//! docs/render.md: the emitters' edges must not be smeared).
//!
//! The library is loaded when a denoise is asked for, not linked: wpbgi builds and runs
//! without it, and `--denoise` without it says in one sentence what to install. Where a user
//! has it, it is found without a variable to set (`library_candidates`): at
//! `WPBGI_OIDN_LIBRARY` when that names a path (then only there), else on the system's search
//! path (`LD_LIBRARY_PATH`, `ld.so.conf`: Intel's release archives), else in PyPI's `pyoidn`
//! wheel (`pip install pyoidn`), which ships the library at `pyoidn/oidn/lib/`: the package of
//! the active virtual or conda environment (`VIRTUAL_ENV`, `CONDA_PREFIX`), then the one the
//! `python3` on `PATH` imports. Debian 12 packages none.
//!
//! Only the C API's stable core is used (OIDN 2: devices, the `RT` filter, shared images).
//! The device runs on the CPU with the render's thread count; its output for one input is the
//! same whatever that count (tests/denoise.rs).

use crate::error::{Error, Result};
use crate::image::Image;
use crate::spectrum::Rgb;
use std::ffi::{c_char, c_int, c_void, CStr};
use std::path::{Path, PathBuf};

/// The environment variable naming the library's path.
pub(crate) const LIBRARY_VARIABLE: &str = "WPBGI_OIDN_LIBRARY";

/// The library's names on the search path, newest first.
const NAMES: [&str; 2] = ["libOpenImageDenoise.so.2", "libOpenImageDenoise.so"];

const DEVICE_TYPE_CPU: c_int = 1;
const FORMAT_FLOAT3: c_int = 3;

type Device = *mut c_void;
type Filter = *mut c_void;

/// The library's entry points this module calls.
struct Api {
    _library: libloading::Library,
    new_device: unsafe extern "C" fn(c_int) -> Device,
    set_device_int: unsafe extern "C" fn(Device, *const c_char, c_int),
    commit_device: unsafe extern "C" fn(Device),
    device_error: unsafe extern "C" fn(Device, *mut *const c_char) -> c_int,
    release_device: unsafe extern "C" fn(Device),
    new_filter: unsafe extern "C" fn(Device, *const c_char) -> Filter,
    set_image: unsafe extern "C" fn(
        Filter,
        *const c_char,
        *mut c_void,
        c_int,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    set_bool: unsafe extern "C" fn(Filter, *const c_char, bool),
    commit_filter: unsafe extern "C" fn(Filter),
    execute_filter: unsafe extern "C" fn(Filter),
    release_filter: unsafe extern "C" fn(Filter),
}

/// What `--denoise` says when the library is missing.
fn missing(reason: &str) -> Error {
    Error::InvalidSetting(format!(
        "--denoise needs Intel Open Image Denoise 2 ({reason}): `pip install pyoidn` into the \
         active Python (wpbgi finds it there), or set {LIBRARY_VARIABLE} to a \
         libOpenImageDenoise.so.2"
    ))
}

/// Where the pyoidn wheel keeps the library, below its package folder.
const WHEEL_LIBRARY: &str = "oidn/lib/libOpenImageDenoise.so.2";

/// Where to look for the library when `WPBGI_OIDN_LIBRARY` names none, in order: the system's
/// search path by [`NAMES`], then the `pyoidn` package below each of `environments` (virtual
/// or conda prefixes: `lib/python3.*/site-packages/pyoidn`). The package the active Python
/// imports comes after these ([`python_package`]), asked only when they all fail: it runs
/// `python3`.
fn library_candidates(environments: &[PathBuf]) -> Vec<std::ffi::OsString> {
    let mut candidates: Vec<std::ffi::OsString> = NAMES.iter().map(Into::into).collect();
    for prefix in environments {
        candidates.extend(
            site_packages(prefix)
                .into_iter()
                .map(|dir| dir.join("pyoidn").join(WHEEL_LIBRARY).into_os_string()),
        );
    }
    candidates
}

/// The `site-packages` folders of the Python environment at `prefix`
/// (`lib/python3.*/site-packages`), sorted by name.
fn site_packages(prefix: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(prefix.join("lib")) else {
        return Vec::new();
    };
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with("python3"))
        .map(|e| e.path().join("site-packages"))
        .filter(|p| p.is_dir())
        .collect();
    found.sort();
    found
}

/// The library at `name` (a path, or a name for the system's search path), loaded.
fn open(name: &std::ffi::OsStr) -> std::result::Result<libloading::Library, String> {
    // SAFETY: loading runs the library's initialisers; OIDN's have no preconditions.
    unsafe { libloading::Library::new(name) }.map_err(|e| e.to_string())
}

/// The active virtual and conda environments' prefixes.
fn active_environments() -> Vec<PathBuf> {
    ["VIRTUAL_ENV", "CONDA_PREFIX"]
        .iter()
        .filter_map(std::env::var_os)
        .map(PathBuf::from)
        .collect()
}

/// The folder of the `pyoidn` package that the `python3` on `PATH` imports, if it has one.
fn python_package() -> Option<PathBuf> {
    let out = std::process::Command::new("python3")
        .args([
            "-c",
            "import os, pyoidn; print(os.path.dirname(os.path.abspath(pyoidn.__file__)))",
        ])
        .stdin(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    let dir = text.trim();
    (out.status.success() && !dir.is_empty()).then(|| PathBuf::from(dir))
}

impl Api {
    fn load() -> Result<Api> {
        if let Some(path) = std::env::var_os(LIBRARY_VARIABLE).filter(|v| !v.is_empty()) {
            return Self::bind(open(&path).map_err(|e| missing(&e))?);
        }
        let library = library_candidates(&active_environments())
            .iter()
            .find_map(|name| open(name).ok())
            .or_else(|| open(python_package()?.join(WHEEL_LIBRARY).as_os_str()).ok())
            .ok_or_else(|| missing("not on the library path, nor in the active Python's pyoidn"))?;
        Self::bind(library)
    }

    fn bind(library: libloading::Library) -> Result<Api> {
        macro_rules! entry {
            ($name:literal) => {
                // SAFETY: the symbol's type is the OIDN 2 C API's declaration of it.
                *unsafe { library.get($name) }
                    .map_err(|e| missing(&format!("it lacks {}: {e}", stringify!($name))))?
            };
        }
        Ok(Api {
            new_device: entry!(b"oidnNewDevice\0"),
            set_device_int: entry!(b"oidnSetDeviceInt\0"),
            commit_device: entry!(b"oidnCommitDevice\0"),
            device_error: entry!(b"oidnGetDeviceError\0"),
            release_device: entry!(b"oidnReleaseDevice\0"),
            new_filter: entry!(b"oidnNewFilter\0"),
            set_image: entry!(b"oidnSetSharedFilterImage\0"),
            set_bool: entry!(b"oidnSetFilterBool\0"),
            commit_filter: entry!(b"oidnCommitFilter\0"),
            execute_filter: entry!(b"oidnExecuteFilter\0"),
            release_filter: entry!(b"oidnReleaseFilter\0"),
            _library: library,
        })
    }

    /// The device's pending error, if any.
    fn check(&self, device: Device) -> Result<()> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: `device` is live; OIDN writes a pointer to a string it owns, or null.
        let code = unsafe { (self.device_error)(device, &mut message) };
        if code == 0 {
            return Ok(());
        }
        let text = if message.is_null() {
            format!("error {code}")
        } else {
            // SAFETY: a NUL-terminated string owned by the device, read before any other call.
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .into_owned()
        };
        Err(Error::InvalidSetting(format!(
            "Intel Open Image Denoise failed: {text}"
        )))
    }
}

/// `beauty` denoised by OIDN's `RT` filter (HDR), guided by `albedo` and `normal` (the first
/// hit's, same size), on `threads` CPU threads (0: the library's choice). The guides are
/// taken as clean (`cleanAux`): they come from the primary hit's exact BSDF and geometry.
pub fn denoise(beauty: &Image, albedo: &Image, normal: &Image, threads: usize) -> Result<Image> {
    let (w, h) = (beauty.width as usize, beauty.height as usize);
    for (name, img) in [("albedo", albedo), ("normal", normal)] {
        if (img.width, img.height) != (beauty.width, beauty.height) {
            return Err(Error::InvalidSetting(format!(
                "the {name} guide is {}x{}, the beauty {w}x{h}",
                img.width, img.height
            )));
        }
    }
    let api = Api::load()?;
    let mut input = beauty.pixels.clone();
    let mut albedo = albedo.pixels.clone();
    let mut normal = normal.pixels.clone();
    let mut output = vec![Rgb::ZERO; w * h];
    let stride = std::mem::size_of::<Rgb>();
    // SAFETY: every call follows the OIDN 2 C API: a device is created, committed and
    // released once; the filter's shared images point into the four buffers above, each
    // w·h tightly packed float triples, which outlive the filter; errors are read from the
    // device after each stage.
    unsafe {
        let device = (api.new_device)(DEVICE_TYPE_CPU);
        if device.is_null() {
            return Err(missing("no CPU device"));
        }
        let result = (|| {
            if threads > 0 {
                let n = c_int::try_from(threads).unwrap_or(c_int::MAX);
                (api.set_device_int)(device, c"numThreads".as_ptr(), n);
            }
            (api.commit_device)(device);
            api.check(device)?;
            let filter = (api.new_filter)(device, c"RT".as_ptr());
            api.check(device)?;
            let image = |name: &CStr, data: *mut Rgb| {
                (api.set_image)(
                    filter,
                    name.as_ptr(),
                    data.cast(),
                    FORMAT_FLOAT3,
                    w,
                    h,
                    0,
                    stride,
                    stride * w,
                )
            };
            image(c"color", input.as_mut_ptr());
            image(c"albedo", albedo.as_mut_ptr());
            image(c"normal", normal.as_mut_ptr());
            image(c"output", output.as_mut_ptr());
            (api.set_bool)(filter, c"hdr".as_ptr(), true);
            (api.set_bool)(filter, c"cleanAux".as_ptr(), true);
            (api.commit_filter)(filter);
            api.check(device)?;
            (api.execute_filter)(filter);
            let done = api.check(device);
            (api.release_filter)(filter);
            done
        })();
        (api.release_device)(device);
        result?;
    }
    // The filter can ring below zero around bright edges; radiance cannot.
    for p in &mut output {
        *p = if p.is_finite() {
            p.max(Rgb::ZERO)
        } else {
            Rgb::ZERO
        };
    }
    Ok(Image {
        width: beauty.width,
        height: beauty.height,
        pixels: output,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The system's names come first, then each environment's wheel (every `python3.*`, in
    /// order); an environment without a `lib` folder adds none.
    #[test]
    fn candidates_are_the_system_then_each_environment() {
        let root = std::env::temp_dir().join(format!("wpbgi-oidn-{}", std::process::id()));
        let env = root.join("venv");
        for version in ["python3.12", "python3.11"] {
            std::fs::create_dir_all(env.join("lib").join(version).join("site-packages"))
                .expect("scratch");
        }
        std::fs::create_dir_all(env.join("lib/ruby")).expect("scratch");
        let found = library_candidates(&[env.clone(), root.join("absent")]);
        let wheel = |v: &str| {
            env.join("lib")
                .join(v)
                .join("site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2")
                .into_os_string()
        };
        let expected: Vec<std::ffi::OsString> = NAMES
            .iter()
            .map(Into::into)
            .chain([wheel("python3.11"), wheel("python3.12")])
            .collect();
        assert_eq!(found, expected);
        std::fs::remove_dir_all(&root).expect("clean up");
    }
}
