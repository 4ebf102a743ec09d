//! The settings structs of the ABI, their defaults, and their translation into the library's
//! settings (the same defaults as `wpbgi bake` and `wpbgi render`).

use crate::guard::{call, checked_mut, checked_str, Failure};
use std::ffi::c_char;
use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::{BakeSettings, Quality};
use wpbgi::render::FinalSettings;

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
    /// Image size in pixels, each side 1 … 16384.
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

/// Fill `settings` with the defaults of `wpbgi bake`: the draft preset, automatic bounces,
/// seed 0, all cores.
///
/// # Safety
/// `settings` must be NULL or point to a writable WpbgiBakeSettings.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_bake_settings_init(settings: *mut WpbgiBakeSettings) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let out = unsafe { checked_mut(settings, "settings") }?;
        *out = WpbgiBakeSettings {
            struct_size: std::mem::size_of::<WpbgiBakeSettings>() as u32,
            quality: 0,
            points: 0,
            light_samples: 0,
            bounces: -1,
            seed: 0,
            threads: 0,
        };
        Ok(())
    })
}

/// Fill `settings` with the defaults of `wpbgi render`: 512 × 512, the scene's camera, 32
/// light samples, seed 0, all cores.
///
/// # Safety
/// `settings` must be NULL or point to a writable WpbgiRenderSettings.
#[no_mangle]
pub unsafe extern "C" fn wpbgi_render_settings_init(settings: *mut WpbgiRenderSettings) -> i32 {
    call(|| {
        // SAFETY: the caller's contract; NULL is refused.
        let out = unsafe { checked_mut(settings, "settings") }?;
        *out = WpbgiRenderSettings {
            struct_size: std::mem::size_of::<WpbgiRenderSettings>() as u32,
            width: 512,
            height: 512,
            light_samples: FinalSettings::default().light_samples,
            camera: std::ptr::null(),
            seed: 0,
            threads: 0,
        };
        Ok(())
    })
}

impl WpbgiBakeSettings {
    /// The library's settings, as `wpbgi bake` builds them from its flags.
    pub(crate) fn to_library(self) -> Result<BakeSettings, Failure> {
        let quality = match self.quality {
            0 => Quality::Draft,
            1 => Quality::Preview,
            2 => Quality::Final,
            3 => Quality::Ultra,
            q => {
                return Err(Failure::InvalidArgument(format!(
                    "settings->quality is {q}; it must be 0 (draft), 1 (preview), 2 (final) or 3 (ultra)"
                )))
            }
        };
        let mut s = BakeSettings::from_quality(quality);
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
            -1 => BounceSettings::auto(),
            n if n >= 0 => BounceSettings::exactly(n as u32),
            n => {
                return Err(Failure::InvalidArgument(format!(
                    "settings->bounces is {n}; it must be -1 (automatic) or a count from 0"
                )))
            }
        };
        Ok(s)
    }
}

/// The most pixels per side, as `wpbgi render --size`.
const MAX_SIDE: u32 = 16384;

impl WpbgiRenderSettings {
    /// The image size, checked.
    pub(crate) fn size(&self) -> Result<(u32, u32), Failure> {
        let ok = |s: u32| (1..=MAX_SIDE).contains(&s);
        if ok(self.width) && ok(self.height) {
            Ok((self.width, self.height))
        } else {
            Err(Failure::InvalidArgument(format!(
                "settings->width and height are {} and {}; each must be 1 … {MAX_SIDE}",
                self.width, self.height
            )))
        }
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
        if self.light_samples == 0 {
            return Err(Failure::InvalidArgument(
                "settings->light_samples must be at least 1".into(),
            ));
        }
        Ok(FinalSettings {
            light_samples: self.light_samples,
            seed: self.seed,
            ..Default::default()
        })
    }
}
