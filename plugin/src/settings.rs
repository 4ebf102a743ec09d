//! The settings structs of the ABI, their defaults, and their translation into the library's
//! settings (the same defaults as `wpbgi bake` and `wpbgi render`).

use crate::guard::{call, checked_mut, checked_str, Failure};
use std::ffi::c_char;
use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::{BakeSettings, Quality};
use wpbgi::render::FinalSettings;
use wpbgi::scene::Camera;

/// How to bake. Initialise it with `wpbgi_bake_settings_init`, then change fields.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct WpbgiBakeSettings {
    /// sizeof(WpbgiBakeSettings), set by the init function; checked by every call.
    pub struct_size: u32,
    /// Quality preset: 0 draft, 1 preview, 2 final, 3 ultra (as `wpbgi bake --quality`).
    pub quality: u32,
    /// Surfels; 0: the preset's.
    pub points: u64,
    /// Emitter samples per surfel; 0: the preset's.
    pub light_samples: u32,
    /// Indirect bounces after the direct light; -1: automatic (until they carry less than
    /// 3 % of the light, then their geometric tail, as `wpbgi bake --bounces auto`); 0: direct light only.
    pub bounces: i32,
    /// Seed of the random streams.
    pub seed: u64,
    /// Worker threads; 0: one per core. The result does not depend on it.
    pub threads: u32,
}

/// What to render and how. Initialise it with `wpbgi_render_settings_init`, then change
/// fields.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct WpbgiRenderSettings {
    /// sizeof(WpbgiRenderSettings), set by the init function; checked by every call.
    pub struct_size: u32,
    /// Image size in pixels, each side from 1 to the library's limit (`wpbgi_render` refuses
    /// a larger one, naming the limit).
    pub width: u32,
    pub height: u32,
    /// Emitter samples per shading point for direct light (final render only).
    pub light_samples: u32,
    /// The scene camera to look through, by name; NULL: the scene's first camera, or one that
    /// frames the scene if it has none.
    pub camera: *const c_char,
    /// Seed of the random streams (final render only).
    pub seed: u64,
    /// Worker threads; 0: one per core. The image does not depend on it.
    pub threads: u32,
}

/// Fill `settings` with the defaults of `wpbgi bake` (the library's `BakeSettings::default()`:
/// the preview preset, automatic bounces), all cores.
///
/// # Safety
/// `settings` must be NULL or point to a writable WpbgiBakeSettings.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_bake_settings_init(settings: *mut WpbgiBakeSettings) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let out = unsafe { checked_mut(settings, "settings") }?;
        let defaults = BakeSettings::default();
        *out = WpbgiBakeSettings {
            struct_size: std::mem::size_of::<WpbgiBakeSettings>() as u32,
            quality: quality_code(Quality::default()),
            points: 0,
            light_samples: 0,
            bounces: bounces_code(&defaults.bounces),
            seed: defaults.seed,
            threads: 0,
        };
        Ok(())
    })
}

/// Fill `settings` with the defaults of `wpbgi render` (the library's `Camera::DEFAULT_SIZE`
/// and `FinalSettings::default()`), the scene's camera, all cores.
///
/// # Safety
/// `settings` must be NULL or point to a writable WpbgiRenderSettings.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_render_settings_init(settings: *mut WpbgiRenderSettings) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let out = unsafe { checked_mut(settings, "settings") }?;
        let defaults = FinalSettings::default();
        let (width, height) = Camera::DEFAULT_SIZE;
        *out = WpbgiRenderSettings {
            struct_size: std::mem::size_of::<WpbgiRenderSettings>() as u32,
            width,
            height,
            light_samples: defaults.light_samples,
            camera: std::ptr::null(),
            seed: defaults.seed,
            threads: 0,
        };
        Ok(())
    })
}

impl WpbgiBakeSettings {
    /// The library's settings, as `wpbgi bake` builds them from its flags.
    pub(crate) fn to_library(self) -> Result<BakeSettings, Failure> {
        let quality = usize::try_from(self.quality)
            .ok()
            .and_then(|q| Quality::ALL.get(q).copied())
            .ok_or_else(|| {
                let codes: Vec<String> = Quality::ALL
                    .iter()
                    .map(|&q| format!("{} ({})", quality_code(q), q.name()))
                    .collect();
                Failure::InvalidArgument(format!(
                    "settings->quality is {}; it must be one of {}",
                    self.quality,
                    codes.join(", ")
                ))
            })?;
        let mut s = BakeSettings::preset(quality);
        if self.points > 0 {
            s.points = usize::try_from(self.points).map_err(|_| {
                Failure::InvalidArgument(format!("settings->points {} is too large", self.points))
            })?;
        }
        if self.light_samples > 0 {
            s.light_samples = self.light_samples;
        }
        s.seed = self.seed;
        s.bounces = match self.bounces {
            AUTO_BOUNCES => BounceSettings::auto(),
            n if n >= 0 => BounceSettings::exactly(n as u32),
            n => {
                return Err(Failure::InvalidArgument(format!(
                    "settings->bounces is {n}; it must be -1 (automatic) or a count from 0"
                )))
            }
        };
        s.validate()
            .map_err(|e| Failure::InvalidArgument(format!("settings: {e}")))?;
        Ok(s)
    }
}

/// The number of preset `q` in `WpbgiBakeSettings::quality`: its place in `Quality::ALL`.
fn quality_code(q: Quality) -> u32 {
    Quality::ALL.iter().position(|&p| p == q).unwrap_or(0) as u32
}

/// `WpbgiBakeSettings::bounces` for automatic bounces.
const AUTO_BOUNCES: i32 = -1;

/// `WpbgiBakeSettings::bounces` for `b`: [`AUTO_BOUNCES`] or the count.
fn bounces_code(b: &BounceSettings) -> i32 {
    if *b == BounceSettings::auto() {
        AUTO_BOUNCES
    } else {
        i32::try_from(b.max).unwrap_or(i32::MAX)
    }
}

impl WpbgiRenderSettings {
    /// The image size, checked.
    pub(crate) fn size(&self) -> Result<(u32, u32), Failure> {
        Camera::check_size(self.width, self.height)
            .map(|()| (self.width, self.height))
            .map_err(|m| Failure::InvalidArgument(format!("settings->width and height: {m}")))
    }

    /// The camera's name, if one is asked for.
    pub(crate) fn camera_name(&self) -> Result<Option<&str>, Failure> {
        if self.camera.is_null() {
            return Ok(None);
        }
        // SAFETY: a non-NULL camera is a NUL-terminated string by the struct's contract.
        unsafe { checked_str(self.camera, "settings->camera") }.map(Some)
    }

    /// The final render's settings, as `wpbgi render` builds them from its defaults.
    pub(crate) fn to_final(self) -> Result<FinalSettings, Failure> {
        let s = FinalSettings {
            light_samples: self.light_samples,
            seed: self.seed,
            ..Default::default()
        };
        s.validate()
            .map_err(|e| Failure::InvalidArgument(format!("settings: {e}")))?;
        Ok(s)
    }
}
