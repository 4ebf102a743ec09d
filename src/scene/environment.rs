//! The environment: radiance arriving from infinitely far away (a USD dome light), as a
//! latitude-longitude map or one colour (docs/design.md §4).
//!
//! Map orientation is OpenEXR's, which UsdLux adopts: in the environment's frame +Y is up,
//! image x runs from longitude +π (left) to −π (right), image y from latitude +π/2 (top) to
//! −π/2 (bottom), and latitude 0, longitude 0 is +Z, longitude π/2 is +X:
//!
//! ω = (cos φ sin λ, sin φ, cos φ cos λ),   u = (1 − λ/π)/2,   v = 1/2 − φ/π.
//!
//! Radiance is looked up bilinearly (wrapping in longitude, clamped in latitude). Sampling is
//! proportional to a piecewise-constant bound of it: each cell of the sampling grid is
//! weighted by the largest luminance its bilinear lookup can reach (the 3 × 3 texels around
//! it) times sin θ, the cell's share of the sphere, so every direction with radiance can be
//! drawn. The density in solid angle is p(u, v) / (2π² sin θ).

use super::texture::{TexRef, Texture, Wrap};
use crate::error::{Error, Result};
use crate::spectrum::{luminance, Rgb};
use glam::{Mat3, Vec2, Vec3, Vec4};
use std::f32::consts::PI;
use std::path::Path;

/// Radiance from every direction not blocked by the scene.
#[derive(Clone, Debug)]
pub struct Environment {
    /// Its name in the scene (for errors and the bake plan).
    pub name: String,
    /// A latitude-longitude map of linear radiance (multiplied by `scale`); `None`: `scale`
    /// from every direction.
    pub map: Option<Texture>,
    /// Multiplies the map (or is the radiance, without one).
    pub scale: Rgb,
    /// World directions to the environment's frame (a rotation).
    pub to_local: Mat3,
}

/// Smallest sampling grid: a constant or tiny map is still sampled close to uniformly over
/// the sphere rather than crowding the poles.
const MIN_GRID: (u32, u32) = (64, 32);

impl Environment {
    /// The same radiance `radiance` from every direction (a white furnace's sky).
    pub fn constant(radiance: Rgb) -> Environment {
        Environment {
            name: format!("constant {} {} {}", radiance.x, radiance.y, radiance.z),
            map: None,
            scale: radiance,
            to_local: Mat3::IDENTITY,
        }
    }

    /// The environment a user names (the command line's `--env`, the plugin's
    /// `wpbgi_scene_set_environment`): `R,G,B` or `V`, one radiance from every direction, or
    /// else the path of a latitude-longitude image ([`Environment::latlong_file`]); times
    /// `intensity`, an image turned by `rotate_degrees` about +Y.
    pub fn from_spec(spec: &str, intensity: f32, rotate_degrees: f32) -> Result<Environment> {
        if !(intensity >= 0.0 && intensity.is_finite()) {
            return Err(Error::InvalidSetting(format!(
                "the environment's intensity must be a non-negative number, got {intensity}"
            )));
        }
        let numbers: Option<Vec<f32>> = spec
            .split(',')
            .map(|t| t.trim().parse::<f32>().ok())
            .collect();
        let radiance = match numbers.as_deref() {
            Some(&[v]) => Some(Vec3::splat(v)),
            Some(&[r, g, b]) => Some(Vec3::new(r, g, b)),
            _ => None,
        };
        match radiance {
            Some(l) if !(l.is_finite() && l.min_element() >= 0.0) => Err(Error::InvalidSetting(
                format!("environment {spec}: the radiance must be non-negative numbers"),
            )),
            Some(l) => Ok(Environment::constant(l * intensity)),
            None => Environment::latlong_file(Path::new(spec), intensity, rotate_degrees),
        }
    }

    /// The latitude-longitude image in `path` (OpenEXR, Radiance HDR, or an 8-bit image read
    /// as sRGB) times `intensity`, turned by `rotate_degrees` about the world's +Y axis (the
    /// map's centre, towards +Z unturned, turns towards +X).
    pub fn latlong_file(path: &Path, intensity: f32, rotate_degrees: f32) -> Result<Environment> {
        let bytes = std::fs::read(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let name = path.display().to_string();
        let (mut map, srgb) = Texture::decode(&name, &bytes).map_err(|reason| {
            Error::InvalidSetting(format!(
                "{name}: not an environment image (latitude-longitude .exr or .hdr): {reason}"
            ))
        })?;
        if srgb {
            map.linearise_srgb();
        }
        if !(intensity >= 0.0 && intensity.is_finite() && rotate_degrees.is_finite()) {
            return Err(Error::InvalidSetting(format!(
                "the environment's intensity must be a non-negative number and its rotation a \
                 number of degrees, got {intensity} and {rotate_degrees}"
            )));
        }
        Ok(Environment {
            name,
            map: Some(map),
            scale: Rgb::splat(intensity),
            // World to the map's frame: the inverse of the turn.
            to_local: Mat3::from_rotation_y(-rotate_degrees.to_radians()),
        })
    }

    /// Radiance arriving from world direction `w` (towards the environment).
    pub fn radiance(&self, w: Vec3) -> Rgb {
        let Some(map) = &self.map else {
            return self.scale;
        };
        let uv = direction_to_uv(self.to_local * w);
        self.scale * MAP_LOOKUP.sample(std::slice::from_ref(map), uv).truncate()
    }

    /// The sampling distribution over directions (built once per render or bake).
    pub fn sampler(&self) -> EnvironmentSampler {
        let (tw, th) = self.map.as_ref().map_or((1, 1), |m| (m.width, m.height));
        let (w, h) = (tw.max(MIN_GRID.0), th.max(MIN_GRID.1));
        let texel_lum = |x: i64, y: i64| -> f32 {
            match &self.map {
                None => luminance(self.scale),
                Some(m) => {
                    let x = x.rem_euclid(m.width as i64) as u32;
                    let y = y.clamp(0, m.height as i64 - 1) as u32;
                    let t = m.texels[(y * m.width + x) as usize];
                    luminance(self.scale * t.truncate()).max(0.0)
                }
            }
        };
        let mut weights = Vec::with_capacity((w * h) as usize);
        for j in 0..h {
            let sin_theta = (PI * (j as f32 + 0.5) / h as f32).sin();
            let ty = (j as u64 * th as u64 / h as u64) as i64;
            for i in 0..w {
                let tx = (i as u64 * tw as u64 / w as u64) as i64;
                let mut most = 0.0f32;
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        most = most.max(texel_lum(tx + dx, ty + dy));
                    }
                }
                weights.push(most * sin_theta);
            }
        }
        EnvironmentSampler {
            grid: Distribution2D::new(&weights, w as usize, h as usize),
        }
    }
}

/// Direction in the environment's frame to map coordinates in [0, 1]².
fn direction_to_uv(l: Vec3) -> Vec2 {
    let l = l.normalize_or(Vec3::Y);
    let latitude = l.y.clamp(-1.0, 1.0).asin();
    let longitude = l.x.atan2(l.z);
    Vec2::new(0.5 * (1.0 - longitude / PI), 0.5 - latitude / PI)
}

/// Map coordinates to a direction in the environment's frame, and sin θ there.
fn uv_to_direction(uv: Vec2) -> (Vec3, f32) {
    let longitude = PI * (1.0 - 2.0 * uv.x);
    let latitude = PI * (0.5 - uv.y);
    let (sl, cl) = longitude.sin_cos();
    let (sp, cp) = latitude.sin_cos();
    (Vec3::new(cp * sl, sp, cp * cl), cp.max(0.0))
}

/// The map's lookup: the bilinear texture lookup of materials, repeating in longitude and
/// clamped at the poles.
const MAP_LOOKUP: TexRef = TexRef {
    texture: 0,
    wrap_s: Wrap::Repeat,
    wrap_t: Wrap::Clamp,
    transform: glam::Affine2::IDENTITY,
    srgb: false,
    scale: Vec4::ONE,
    bias: Vec4::ZERO,
};

/// Draws directions from an [`Environment`] in proportion to its radiance.
#[derive(Clone, Debug)]
pub struct EnvironmentSampler {
    grid: Distribution2D,
}

impl EnvironmentSampler {
    /// Whether the environment has no radiance anywhere.
    pub(crate) fn is_black(&self) -> bool {
        self.grid.total <= 0.0
    }

    /// ∫ weight du dv over the map: the relative power used to choose among emitters.
    pub fn integral(&self) -> f64 {
        self.grid.total / (self.grid.width * self.grid.height) as f64
    }

    /// A world direction for `u` and its solid-angle density (`None` where it is 0).
    pub fn sample(&self, env: &Environment, u: Vec2) -> Option<(Vec3, f32)> {
        let (uv, pdf_uv) = self.grid.sample(u)?;
        let (local, sin_theta) = uv_to_direction(uv);
        if sin_theta <= 0.0 {
            return None;
        }
        let pdf = pdf_uv / (2.0 * PI * PI * sin_theta);
        let w = (env.to_local.transpose() * local).normalize();
        (pdf > 0.0 && pdf.is_finite()).then_some((w, pdf))
    }

    /// The solid-angle density with which [`EnvironmentSampler::sample`] draws world
    /// direction `w`.
    pub fn pdf(&self, env: &Environment, w: Vec3) -> f32 {
        let l = (env.to_local * w).normalize_or(Vec3::Y);
        let sin_theta = (1.0 - l.y * l.y).max(0.0).sqrt();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        self.grid.pdf(direction_to_uv(l)) / (2.0 * PI * PI * sin_theta)
    }
}

/// A piecewise-constant density over [0, 1]² on a `width × height` grid: a marginal over rows
/// and a conditional over each row's cells (pbrt's `PiecewiseConstant2D`).
#[derive(Clone, Debug)]
struct Distribution2D {
    width: usize,
    height: usize,
    /// Cumulative weights within each row (`width` per row, ending at the row's sum).
    rows: Vec<f64>,
    /// Cumulative row sums.
    marginal: Vec<f64>,
    total: f64,
}

impl Distribution2D {
    fn new(weights: &[f32], width: usize, height: usize) -> Self {
        let mut rows = Vec::with_capacity(weights.len());
        let mut marginal = Vec::with_capacity(height);
        let mut total = 0.0f64;
        for r in weights.chunks(width) {
            let mut acc = 0.0f64;
            for &w in r {
                acc += w.max(0.0) as f64;
                rows.push(acc);
            }
            total += acc;
            marginal.push(total);
        }
        Distribution2D {
            width,
            height,
            rows,
            marginal,
            total,
        }
    }

    /// Pick a cell by `u.y` (row) then `u.x` (column), and place the point within it.
    fn sample(&self, u: Vec2) -> Option<(Vec2, f32)> {
        if self.total <= 0.0 {
            return None;
        }
        let pick = |cdf: &[f64], total: f64, u: f32| -> Option<(usize, f32)> {
            let target = u as f64 * total;
            let i = cdf.partition_point(|&c| c <= target).min(cdf.len() - 1);
            let prev = if i == 0 { 0.0 } else { cdf[i - 1] };
            let width = cdf[i] - prev;
            (width > 0.0).then(|| (i, (((target - prev) / width) as f32).clamp(0.0, 1.0)))
        };
        let (j, fy) = pick(&self.marginal, self.total, u.y)?;
        let row = &self.rows[j * self.width..(j + 1) * self.width];
        let (i, fx) = pick(row, row[self.width - 1], u.x)?;
        let uv = Vec2::new(
            (i as f32 + fx) / self.width as f32,
            (j as f32 + fy) / self.height as f32,
        );
        Some((uv, self.cell_pdf(i, j)))
    }

    fn cell_pdf(&self, i: usize, j: usize) -> f32 {
        let k = j * self.width + i;
        let prev = if i == 0 { 0.0 } else { self.rows[k - 1] };
        let cell = self.rows[k] - prev;
        (cell / self.total * (self.width * self.height) as f64) as f32
    }

    /// Density at `uv` (with respect to area in [0, 1]²).
    fn pdf(&self, uv: Vec2) -> f32 {
        if self.total <= 0.0 {
            return 0.0;
        }
        let i = ((uv.x * self.width as f32) as usize).min(self.width - 1);
        let j = ((uv.y * self.height as f32) as usize).min(self.height - 1);
        self.cell_pdf(i, j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_and_map_coordinates_round_trip() {
        // OpenEXR's axes: +Z at the image centre, +X a quarter to the left of it, +Y at the top.
        let z = direction_to_uv(Vec3::Z);
        assert!((z - Vec2::new(0.5, 0.5)).length() < 1e-6, "{z}");
        let x = direction_to_uv(Vec3::X);
        assert!((x - Vec2::new(0.25, 0.5)).length() < 1e-6, "{x}");
        assert!(direction_to_uv(Vec3::Y).y.abs() < 1e-6);
        for k in 0..50 {
            let uv = Vec2::new((k as f32 * 0.618).fract(), 0.02 + 0.96 * k as f32 / 50.0);
            let (w, _) = uv_to_direction(uv);
            let back = direction_to_uv(w);
            // u = 0 and u = 1 are the same meridian.
            let du = (back.x - uv.x).abs();
            let du = du.min(1.0 - du);
            assert!(
                du < 1e-4 && (back.y - uv.y).abs() < 1e-4,
                "{uv} → {w} → {back}"
            );
        }
    }

    /// The density integrates to 1 over the sphere, and sampling draws what `pdf` says:
    /// E[1/p] = 4π over the sphere, for a map with a bright spot.
    #[test]
    fn sampling_density_is_normalised_and_consistent() {
        let (w, h) = (16u32, 8u32);
        let mut texels = vec![Vec4::new(0.1, 0.1, 0.1, 1.0); (w * h) as usize];
        texels[(2 * w + 5) as usize] = Vec4::new(50.0, 40.0, 30.0, 1.0);
        let env = Environment {
            name: "test".into(),
            map: Some(Texture {
                name: "spot".into(),
                width: w,
                height: h,
                texels,
            }),
            scale: Rgb::ONE,
            to_local: Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(0.3),
        };
        let sampler = env.sampler();
        // ∫ p dω by a fine midpoint rule over (θ, φ).
        let (n_t, n_p) = (400, 800);
        let mut integral = 0.0f64;
        for a in 0..n_t {
            let theta = PI * (a as f32 + 0.5) / n_t as f32;
            for b in 0..n_p {
                let phi = 2.0 * PI * (b as f32 + 0.5) / n_p as f32;
                let d = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                integral += (sampler.pdf(&env, d) * theta.sin()) as f64;
            }
        }
        integral *= (PI as f64 / n_t as f64) * (2.0 * PI as f64 / n_p as f64);
        assert!((integral - 1.0).abs() < 2e-3, "∫ p dω = {integral}");
        let n = 20_000;
        let (mut inv, mut mismatched) = (0.0f64, 0);
        for k in 0..n {
            let u = Vec2::new(
                (k as f32 + 0.5) / n as f32,
                (((k as u64 * 7919) % n as u64) as f32 + 0.5) / n as f32,
            );
            let (d, p) = sampler.sample(&env, u).expect("sample");
            // The same cell's density, except where rounding moves a point on a cell's
            // border into its neighbour.
            if (p - sampler.pdf(&env, d)).abs() > 1e-3 * p {
                mismatched += 1;
            }
            inv += 1.0 / p as f64;
        }
        assert!(
            mismatched < n / 1000,
            "{mismatched} of {n} samples' densities differ"
        );
        let four_pi = 4.0 * std::f64::consts::PI;
        assert!(
            (inv / n as f64 - four_pi).abs() < 0.02 * four_pi,
            "E[1/p] = {}",
            inv / n as f64
        );
    }
}
