//! What the camera sees before the gather (docs/design.md §7, docs/method.md §2.3 step 0): the primary hit,
//! emission, direct light by ray tracing, and for receivers smoother than the specular cut-off
//! their reflection / refraction chain, followed by ray tracing to the first rough hit.
//!
//! Every rough hit becomes a [`Receiver`] of indirect light, weighted by the throughput that
//! led to it; the gather fills in its indirect light later.
//!
//! Path depth follows Mitsuba's `max_depth` (segments): a rough hit reached over `c` chain
//! vertices shows emission if `c + 1 ≤ max_depth`, direct light if `c + 2 ≤ max_depth`, and
//! the cache's light (one bounce of a direct-only bake) if `c + 3 ≤ max_depth`.

use crate::accel::{Accel, Segment, OCCLUSION_SET};
use crate::bsdf::fresnel::fresnel_dielectric;
use crate::bsdf::{Bsdf, TransportMode};
use crate::emitters::{shadowed, Draw};
use crate::geometry::frame::Frame;
use crate::geometry::offset::offset_origin;
use crate::sampler::{mix64, permute, sobol02, Sampler, GOLDEN_GAMMA};
use crate::spectrum::{max_component, Rgb};
use crate::trace::{intersect, mis, SurfaceHit, Tracer};
use glam::{Vec3, Vec3A};

/// A rough surface point that gathers indirect light from the cache.
#[derive(Clone, Debug)]
pub struct Receiver {
    /// Where its light goes: the image pixel (row-major).
    pub pixel: u32,
    /// Throughput from the camera sample to this point, over the pixel's sample count.
    pub weight: Rgb,
    /// The surface point.
    pub p: Vec3,
    /// The rounding bound of `p`, to leave the surface by with `ng`
    /// ([`crate::geometry::offset::offset_origin`]).
    pub err: Vec3,
    /// The hit triangle's geometric normal.
    pub ng: Vec3,
    /// The mesh it lies on.
    pub mesh: u32,
    /// Its shading frame (shading normal and tangents).
    pub frame: Frame,
    /// Its BSDF at this point (textures applied).
    pub bsdf: Bsdf,
    /// Direction towards the viewer, in `frame`.
    pub view: Vec3,
    /// Which specular chain led here from the camera: 0 for a primary hit, otherwise a hash
    /// of the meshes it met and the branch it took at each (reflection or refraction).
    /// Neighbouring pixels' receivers with the same chain see one surface through the same
    /// mirrors and glass, as primary hits see it directly ([`super::sparse`]).
    pub chain: u64,
    /// The quarter of its pixel whose gathering sample it came from (0–3, x first), or `None`
    /// for a pixel of one sample.
    pub quarter: Option<u8>,
}

impl Receiver {
    /// The origin of a ray leaving the receiver along `w`, offset to the side `w` points to
    /// by the rounding bound of its point (as [`crate::trace::SurfaceHit::spawn`]).
    pub fn spawn(&self, w: Vec3) -> Vec3 {
        Vec3::from(offset_origin(
            Vec3A::from(self.p),
            Vec3A::from(self.err),
            Vec3A::from(self.ng),
            Vec3A::from(w),
        ))
    }
}

/// The chain `chain` continued at mesh `mesh` by branch `branch` (see [`Receiver::chain`]):
/// a SplitMix64 step over the pair, never 0.
fn extend_chain(chain: u64, mesh: u32, branch: usize) -> u64 {
    let step = ((u64::from(mesh) << 8) | branch as u64).wrapping_add(GOLDEN_GAMMA);
    mix64(chain ^ step).max(1)
}

/// What one camera sample contributes directly, and the first hit's AOVs.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PrimarySample {
    /// Emission and direct light.
    pub direct: Rgb,
    /// The first hit's albedo (the BSDF's reflectance), the denoiser's guide.
    pub albedo: Rgb,
    /// The first hit's shading normal, the denoiser's guide.
    pub normal: Vec3,
    /// Distance to the first hit (∞ for none).
    pub depth: f32,
    /// Coverage: the fraction of the pixel's camera samples that hit the scene (set per
    /// pixel by the render; 0 for one sample).
    pub alpha: f32,
}

/// The settings the primary pass reads.
#[derive(Clone, Copy, Debug)]
pub struct PrimarySettings {
    /// Longest path in segments, Mitsuba's `max_depth` (−1: unlimited).
    pub max_depth: i32,
    /// Emitter samples per pixel at each rough hit (and as many BSDF samples for glossy
    /// ones), shared among the pixel's camera samples ([`LightShare`]).
    pub light_samples: u32,
    /// Receivers with roughness below this follow their chain instead of gathering.
    pub specular_below: f32,
    /// Longest specular chain, in vertices.
    pub chain_depth: u32,
    /// A mirror or clear-glass pixel without an edge gathers once per quarter, as an edge
    /// does, instead of once (`render/pixels.rs`): the paths gather wants the rays of four
    /// receivers there (cbox-mirror, 256², 16 rays, denoised: relMSE 2.54e-3 with one,
    /// 2.27e-3 with four); the buffers' gathers interpolate instead.
    pub smooth_quarters: bool,
    /// Whether a diffuse hit whose direct light has a closed form takes half its share of
    /// light samples (`LightShare::halved`): in frames of [`HALVED_FROM`] pixels and more on
    /// their shorter side.
    pub halve_closed_form: bool,
    /// Seed of the per-pixel random sequences.
    pub seed: u64,
}

/// The smallest frame (shorter side, in pixels) in which a diffuse hit whose direct light has
/// a closed form takes half its share of light samples. At 512² the halved shadow rays cost
/// cbox-diffuse +0.5 % relMSE and saved 28 % of its primary pass; at 256², where a pixel's noise
/// is not averaged with its neighbours', +1.6 % (docs/render.md). Decided by the whole frame,
/// so that a crop samples as its frame does.
pub const HALVED_FROM: u32 = 512;

/// A branch of a specular chain (the reflection or refraction of a mirror or clear glass) is
/// followed while its throughput, largest channel, exceeds this fraction of its camera
/// sample's weight. Below it lie the second and later reflections inside a glass, and grazing
/// ones: each one more hit, direct light at its end, and a receiver on a layer of its own,
/// whose differences between neighbouring pixels also made edges of the glass's pixels
/// (`render/pixels.rs`). At 512² (docs/render.md) 1e-3 instead of 1e-4 took 11–20 % off the
/// renders of cbox-glossy, cbox-mirror and caustic at the same relMSE against Mitsuba's
/// references (+0.005 % to −0.24 %), and moved cbox-glossy's glass pixels by 1.3e-4 of their
/// light on average; 2e-3 took caustic 19 % further from every receiver gathering
/// (`--dense`), 1e-3 4 %.
pub(crate) const FAINT_BRANCH: f32 = 1e-3;

/// Whether a path of `segments` segments is within `max_depth` (−1: unlimited).
fn within(max_depth: i32, segments: u32) -> bool {
    max_depth < 0 || segments as i64 <= max_depth as i64
}

/// A camera sample: its ray, pixel, weight in the pixel, and the weight of its receivers
/// (`None`: it gathers nothing, another sample of the pixel gathers for it).
#[derive(Clone, Copy, Debug)]
pub(crate) struct CameraSample {
    /// Ray origin.
    pub o: Vec3,
    /// Ray direction (unit).
    pub d: Vec3,
    /// The pixel (row-major).
    pub pixel: u32,
    /// Its weight in the pixel's mean.
    pub weight: Rgb,
    /// The weight of the receivers it makes.
    pub gather_weight: Option<Rgb>,
    /// The quarter of the pixel it gathers for, when the pixel has several samples.
    pub quarter: Option<u8>,
    /// Its share of the pixel's direct-light samples.
    pub light: LightShare,
}

/// Which of its pixel's direct-light samples a camera sample takes at each rough hit:
/// `count` of them from index `first`, of the pixel's `total`. A pixel of many camera samples
/// (an edge, a mirror or clear glass) spreads [`PrimarySettings::light_samples`] over them
/// instead of taking that many at each. The pixel's light points are one xor-scrambled
/// (0, 2)-sequence (`scramble`, the pixel's), and each camera sample takes a block of
/// `count` consecutive points, the blocks handed out in an order shuffled per pixel
/// (Kensler's permutation, `sampler::permute`): together the samples' points are the sequence's first
/// `total`, stratified over the emitters and over each emitter's surface as one plain pixel's
/// are, and which block a sample takes is independent of where in the pixel it lies. (In
/// block order, sample s took points from index s · count, whose high bits are s's, as its
/// own (0, 2)-point in the pixel is: on a diffuse cube's edges under a constant environment
/// the pixels came out up to 29 % off. Each sample's own scramble instead left the pixel's
/// points unstratified, and it took 8 points at each camera sample for an edge's 64 samples
/// to stay within the plain pixels' spread: 512 shadow rays where a plain pixel takes 32.)
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightShare {
    /// Index of its first sample among the pixel's.
    pub first: u32,
    /// How many samples it takes.
    pub count: u32,
    /// How many the pixel takes in all.
    pub total: u32,
    /// The xor scramble of the pixel's sequence of light points.
    pub scramble: [u32; 2],
}

impl LightShare {
    /// The fewest direct-light samples a camera sample takes: a block of two consecutive
    /// points of the (0, 2)-sequence lies one in each half of its domain, so each camera
    /// sample's own estimate is stratified, which one point is not. On a diffuse cube's edges
    /// under a constant environment (tests/bake_cli.rs, 48², the pixels whose 3 × 3
    /// neighbourhood lies on the cube) the worst pixel came out 29.6 % off ρL at one point per
    /// camera sample, 11.9 % at two, 11.4 % at four, 9.9 % at eight, and 16.2 % with each
    /// sample's eight points scrambled on their own (the scheme this replaced). At two, an edge
    /// pixel's 64 camera samples take 128 shadow rays where they took 512. (One seed's worst
    /// pixel is itself noisy: with the order's seed drawn whole, 32 bits, the same pixels
    /// came out 14.0 % off, and 11.5–17.6 % under seeds 1 to 6.)
    pub(crate) const LEAST: u32 = 2;

    /// The share a hit whose direct light has a closed form takes (see `direct_light`): half
    /// as many samples (at least [`LightShare::LEAST`] where there are as many), stratified
    /// over the first half of the pixel's points as the share is over all of them. At 512², at
    /// half the shadow rays, the ratio estimator came within 0.5 % of the plain one's relMSE
    /// against Mitsuba at full count on the five reference scenes (docs/render.md).
    pub(crate) fn halved(self) -> LightShare {
        let half = (self.count / 2).max(Self::LEAST.min(self.count));
        if half == self.count || self.count == 0 {
            return self;
        }
        LightShare {
            first: self.first / self.count * half,
            count: half,
            total: self.total / self.count * half,
            scramble: self.scramble,
        }
    }

    /// No direct-light samples: for tracing a camera sample's chain alone.
    pub(crate) const NONE: LightShare = LightShare {
        first: 0,
        count: 0,
        total: 0,
        scramble: [0, 0],
    };

    /// The share of camera sample `sample` of a pixel of `samples`, for `light_samples` per
    /// pixel (at least 1; `render_final` refuses 0), with the pixel's `scramble` of its light
    /// points and `shuffle` of the order it hands them out in.
    pub(crate) fn of_sample(
        light_samples: u32,
        sample: u32,
        samples: u32,
        (scramble, shuffle): ([u32; 2], u32),
    ) -> Self {
        let samples = samples.max(1);
        let count = light_samples
            .div_ceil(samples)
            .max(Self::LEAST.min(light_samples));
        LightShare {
            first: permute(sample, samples, shuffle) * count,
            count,
            total: count * samples,
            scramble,
        }
    }
}

/// Trace camera sample `cs`, pushing its receivers.
pub(crate) fn trace_primary(
    ctx: &Tracer,
    settings: &PrimarySettings,
    cs: CameraSample,
    sampler: &mut Sampler,
    receivers: &mut Vec<Receiver>,
) -> PrimarySample {
    let CameraSample {
        o,
        d,
        pixel,
        weight,
        gather_weight,
        quarter,
        light,
    } = cs;
    let gather_scale = gather_weight.map(|g| g / weight);
    let mut out = PrimarySample {
        depth: f32::INFINITY,
        ..Default::default()
    };
    let mut stack = vec![(o, d, weight, 0u32, 0u64)];
    let mut first = true;
    while let Some((o, d, throughput, chain, path)) = stack.pop() {
        let Some(hit) = intersect(ctx, o, d) else {
            // The environment, seen directly or along the chain.
            if let Some(env) = &ctx.scene.environment {
                if within(settings.max_depth, chain + 1) {
                    out.direct += throughput * env.radiance(d);
                }
            }
            continue;
        };
        let material = &ctx.scene.materials[ctx.scene.meshes[hit.mesh as usize].material];
        let bsdf = material.bsdf_at(&ctx.scene.textures, hit.uv);
        let view = hit.frame.to_local(-d);
        if first {
            out.albedo = bsdf.albedo_estimate();
            out.normal = hit.frame.n;
            out.depth = hit.t;
            first = false;
        }
        if within(settings.max_depth, chain + 1) {
            let le = material.emission_at(&ctx.scene.textures, hit.uv, view.z > 0.0);
            out.direct += throughput * le;
        }
        let smooth = bsdf.alpha().is_some_and(|a| a < settings.specular_below);
        if smooth {
            if chain < settings.chain_depth && within(settings.max_depth, chain + 2) {
                for (branch, wo, w) in specular_branches(&bsdf, view, sampler) {
                    let t = throughput * w;
                    if max_component(t) > FAINT_BRANCH * max_component(weight) && t.is_finite() {
                        let world = hit.frame.to_world(wo).normalize();
                        let path = extend_chain(path, hit.mesh, branch);
                        stack.push((hit.spawn(world), world, t, chain + 1, path));
                    }
                }
            }
            continue;
        }
        if !bsdf.is_two_sided() && view.z <= 0.0 {
            continue;
        }
        if within(settings.max_depth, chain + 2) {
            let hit_light = (light, settings.halve_closed_form);
            out.direct += throughput * direct_light(ctx, hit_light, &hit, &bsdf, view, sampler);
        }
        if let Some(scale) = gather_scale.filter(|_| within(settings.max_depth, chain + 3)) {
            receivers.push(Receiver {
                pixel,
                weight: throughput * scale,
                p: hit.p,
                err: hit.err,
                ng: hit.ng,
                mesh: hit.mesh,
                frame: hit.frame,
                bsdf,
                view,
                chain: path,
                quarter,
            });
        }
    }
    if !out.direct.is_finite() {
        out.direct = Rgb::ZERO;
    }
    out
}

/// The branches of a smooth surface: its mirror reflection and (for dielectrics) its
/// refraction, each with its weight, so that the chain is deterministic instead of picking a
/// branch at random. The BSDF is still sampled (its roughness, however small, is Mitsuba's).
/// Each branch comes with its index: 0 reflects, 1 refracts.
fn specular_branches(bsdf: &Bsdf, view: Vec3, sampler: &mut Sampler) -> Vec<(usize, Vec3, Rgb)> {
    let u = sampler.next_2d();
    let sample = |u0: f32| bsdf.sample(view, u0, u, TransportMode::Radiance);
    match bsdf {
        Bsdf::Dielectric(b) => {
            // Lobe selection by Fresnel: u0 below F reflects. Each branch's weight is its
            // sample weight times its selection probability.
            let f = fresnel_dielectric(view.z, b.eta).r;
            let mut out = Vec::new();
            if f > 0.0 {
                if let Some(s) = sample(0.0) {
                    out.push((0, s.wo, s.weight * f));
                }
            }
            if f < 1.0 {
                if let Some(s) = sample(1.0 - f32::EPSILON) {
                    out.push((1, s.wo, s.weight * (1.0 - f)));
                }
            }
            out
        }
        _ => sample(sampler.next_1d())
            .map(|s| (usize::from(s.wo.z < 0.0), s.wo, s.weight))
            .into_iter()
            .collect(),
    }
}

/// Emitter samples waiting for their shadow rays: up to [`OCCLUSION_SET`] segments, each
/// with the light it brings if nothing blocks it.
struct ShadowSet {
    segments: [Segment; OCCLUSION_SET],
    light: [Rgb; OCCLUSION_SET],
    len: usize,
}

impl ShadowSet {
    fn new() -> ShadowSet {
        let none = Segment {
            origin: Vec3::ZERO,
            dir: Vec3::ZERO,
            tmin: 0.0,
            tmax: 0.0,
        };
        ShadowSet {
            segments: [none; OCCLUSION_SET],
            light: [Rgb::ZERO; OCCLUSION_SET],
            len: 0,
        }
    }

    /// Queue a sample; a full set is tested first, its light added to `sum`.
    fn push(&mut self, segment: Segment, light: Rgb, accel: &Accel, sum: &mut Rgb) {
        if self.len == OCCLUSION_SET {
            self.add_visible(accel, sum);
        }
        self.segments[self.len] = segment;
        self.light[self.len] = light;
        self.len += 1;
    }

    /// Add the light of the unblocked samples to `sum`, one by one in the order they came
    /// (the sums one sample at a time would make, bit for bit), and empty the set.
    fn add_visible(&mut self, accel: &Accel, sum: &mut Rgb) {
        if self.len == 0 {
            return;
        }
        let blocked = accel.occluded_set(&self.segments[..self.len]);
        for (i, &light) in self.light[..self.len].iter().enumerate() {
            if blocked >> i & 1 == 0 {
                *sum += light;
            }
        }
        self.len = 0;
    }
}

/// Direct light at a rough hit: the emitter samples of `share`, stratified over the emitters
/// other than the delta lights and over each emitter's surface; for glossy BSDFs as many BSDF
/// samples, combined by the power heuristic; and each delta light once, exactly
/// ([`Draw::WithoutDelta`]). Returns the outgoing radiance towards `view`.
fn direct_light(
    ctx: &Tracer,
    (share, halve_closed_form): (LightShare, bool),
    hit: &SurfaceHit,
    bsdf: &Bsdf,
    view: Vec3,
    sampler: &mut Sampler,
) -> Rgb {
    if share.count == 0 {
        return Rgb::ZERO;
    }
    // A diffuse surface under a few triangles of constant radiance: their unshadowed light in
    // closed form, scaled by the share of it the shadow rays find unblocked (`shadowed`), from
    // half the shadow rays in large frames.
    let closed_form = match bsdf {
        Bsdf::Diffuse(d) if view.z > 0.0 => ctx.emitters.closed_form().map(|light| {
            d.reflectance * std::f32::consts::FRAC_1_PI * light.irradiance(hit.p, hit.frame.n)
        }),
        _ => None,
    };
    let share = if closed_form.is_some() && halve_closed_form {
        share.halved()
    } else {
        share
    };
    let LightShare {
        first,
        count: k,
        total,
        scramble,
    } = share;
    let stratum =
        |i: u32, shift: f32| (((first + i) as f32 + shift) / total as f32).min(1.0 - f32::EPSILON);
    let glossy = !matches!(bsdf, Bsdf::Diffuse(_));
    let mut unshadowed = Rgb::ZERO;
    let shift = sampler.next_1d();
    let mut sum = Rgb::ZERO;
    // The samples' shadow rays go in sets that traverse the tree together; their light is
    // added in sample order once the set is tested, as one at a time would add it.
    let mut set = ShadowSet::new();
    for i in 0..k {
        let Some(es) = ctx.emitters.sample(
            ctx.scene,
            hit.p,
            (stratum(i, shift), sobol02(first + i, scramble)),
            Draw::WithoutDelta,
        ) else {
            continue;
        };
        let wo = hit.frame.to_local(es.wi);
        let f = bsdf.eval(view, wo, TransportMode::Radiance);
        if f == Rgb::ZERO {
            continue;
        }
        let w = if es.delta || !glossy {
            1.0
        } else {
            mis(es.pdf, bsdf.pdf(view, wo))
        };
        let segment = es.shadow_segment(hit.spawn(es.wi));
        unshadowed += f * es.value * w;
        set.push(segment, f * es.value * w, &ctx.accel, &mut sum);
    }
    set.add_visible(&ctx.accel, &mut sum);
    if let Some(exact) = closed_form {
        return shadowed(exact, sum, unshadowed);
    }
    // The delta lights, each once and exactly (`Draw::WithoutDelta`), beside the samples'
    // mean.
    let mut delta = Rgb::ZERO;
    for es in ctx
        .emitters
        .delta_lights(ctx.scene, hit.p, Draw::WithoutDelta)
    {
        let f = bsdf.eval(view, hit.frame.to_local(es.wi), TransportMode::Radiance);
        if f != Rgb::ZERO {
            let segment = es.shadow_segment(hit.spawn(es.wi));
            set.push(segment, f * es.value, &ctx.accel, &mut delta);
        }
    }
    set.add_visible(&ctx.accel, &mut delta);
    if glossy {
        let scramble = [scramble[1] ^ 0x5bd1_e995, scramble[0] ^ 0x1b87_3593];
        for i in 0..k {
            let Some(bs) = bsdf.sample(
                view,
                stratum(i, shift),
                sobol02(first + i, scramble),
                TransportMode::Radiance,
            ) else {
                continue;
            };
            let dir = hit.frame.to_world(bs.wo).normalize();
            let origin = hit.spawn(dir);
            if !ctx.may_reach_emitter(origin, dir) {
                continue;
            }
            let Some(h) = intersect(ctx, origin, dir) else {
                if let Some(env) = &ctx.scene.environment {
                    let w = mis(
                        bs.pdf,
                        ctx.emitters
                            .pdf_environment(ctx.scene, dir, Draw::WithoutDelta),
                    );
                    sum += bs.weight * env.radiance(dir) * w;
                }
                continue;
            };
            let m = &ctx.scene.materials[ctx.scene.meshes[h.mesh as usize].material];
            if m.emission.is_none() {
                continue;
            }
            let le = m.emission_at(&ctx.scene.textures, h.uv, h.frame.to_local(-dir).z > 0.0);
            if le == Rgb::ZERO {
                continue;
            }
            let w = mis(
                bs.pdf,
                ctx.emitters
                    .pdf_hit(h.mesh, h.triangle, h.t, dir, h.ng, Draw::WithoutDelta),
            );
            sum += bs.weight * le * w;
        }
    }
    sum / k as f32 + delta
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Diffuse;
    use crate::scene::{Emission, Material, Mesh, Scattering, Scene};

    /// Asserts that `shares`, of one pixel with `light_samples`, take its first `total` light
    /// points once each (one total and scramble among them, each at least
    /// [`LightShare::LEAST`] or all there are); returns the total.
    fn takes_each_point_once(shares: &[LightShare], light_samples: u32) -> u32 {
        let (total, scramble) = (shares[0].total, shares[0].scramble);
        let mut taken = vec![0; total as usize];
        for share in shares {
            assert_eq!((share.total, share.scramble), (total, scramble));
            assert!(share.count >= LightShare::LEAST.min(light_samples));
            for i in share.first..share.first + share.count {
                taken[i as usize] += 1;
            }
        }
        let label = format!("{light_samples} over {}", shares.len());
        assert!(taken.iter().all(|&n| n == 1), "{label}");
        total
    }

    /// The shares of a pixel's camera samples, halved, still take the first half of its light
    /// points once each, every one at least [`LightShare::LEAST`].
    #[test]
    fn halved_shares_take_the_first_half_of_the_points_once_each() {
        for light_samples in [2, 3, 8, 32] {
            for samples in [1, 4, 16, 64] {
                let shares: Vec<LightShare> = (0..samples)
                    .map(|s| LightShare::of_sample(light_samples, s, samples, ([1, 2], 7)))
                    .map(LightShare::halved)
                    .collect();
                let total = takes_each_point_once(&shares, light_samples);
                let whole = LightShare::of_sample(light_samples, 0, samples, ([1, 2], 7));
                assert!(2 * total <= whole.total + samples * LightShare::LEAST);
            }
        }
    }

    /// A floor under a square light of constant radiance, and a blocker that hides part of
    /// the floor from all of it.
    fn floor_under_a_light() -> Scene {
        let quad = |corners: [Vec3; 4], material: usize, name: &str| Mesh {
            name: name.into(),
            positions: corners.to_vec(),
            normals: None,
            uvs: None,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            material,
        };
        let material = |name: &str, reflectance: f32, emission: Option<Emission>| Material {
            name: name.into(),
            scattering: Scattering::Explicit(Bsdf::Diffuse(Diffuse {
                reflectance: Rgb::splat(reflectance),
            })),
            cutout: None,
            normal_map: None,
            emission,
        };
        let light = Emission {
            radiance: Rgb::new(4.0, 3.0, 2.0),
            texture: None,
            two_sided: false,
        };
        Scene {
            meshes: vec![
                quad(
                    [
                        Vec3::new(-4.0, -4.0, 0.0),
                        Vec3::new(4.0, -4.0, 0.0),
                        Vec3::new(4.0, 4.0, 0.0),
                        Vec3::new(-4.0, 4.0, 0.0),
                    ],
                    0,
                    "floor",
                ),
                // Facing down (clockwise seen from above).
                quad(
                    [
                        Vec3::new(-1.0, -1.0, 1.0),
                        Vec3::new(-1.0, 1.0, 1.0),
                        Vec3::new(1.0, 1.0, 1.0),
                        Vec3::new(1.0, -1.0, 1.0),
                    ],
                    1,
                    "light",
                ),
                // A blocker at x ≥ 2.5 from z = 0.2 up to 1.5, hiding the floor beyond x = 3.
                quad(
                    [
                        Vec3::new(2.5, -4.0, 0.2),
                        Vec3::new(2.5, 4.0, 0.2),
                        Vec3::new(2.5, 4.0, 1.5),
                        Vec3::new(2.5, -4.0, 1.5),
                    ],
                    0,
                    "blocker",
                ),
            ],
            materials: vec![
                material("floor", 0.5, None),
                material("light", 0.0, Some(light)),
            ],
            ..Default::default()
        }
    }

    /// A diffuse floor that sees all of the light gets its direct light exactly (ρ/π times
    /// the square's irradiance in closed form, the corner-rectangle formula), from any number
    /// of samples, and a part that sees none gets none.
    #[test]
    fn unshadowed_diffuse_direct_light_is_exact_from_few_samples() {
        let scene = floor_under_a_light();
        let ctx = Tracer::new(&scene);
        assert!(ctx.emitters.closed_form().is_some());
        // The irradiance of a rectangle [0, a] × [0, b] at height c over the receiver, corner
        // above it, per unit radiance: π F with F the corner-rectangle form factor.
        let corner = |a: f64, b: f64, c: f64| {
            let (x, y) = (a / c, b / c);
            let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
            0.5 * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan())
        };
        for (at, under) in [((0.0, 0.0), true), ((0.3, -0.6), true), ((3.5, 0.2), false)] {
            let (px, py): (f64, f64) = at;
            let (dx, dy) = ([-1.0 - px, 1.0 - px], [-1.0 - py, 1.0 - py]);
            // Signed sum of the four corner rectangles between the receiver's foot and the
            // square's corners.
            let mut e = 0.0;
            for (i, &x) in dx.iter().enumerate() {
                for (j, &y) in dy.iter().enumerate() {
                    let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
                    e += sign * x.signum() * y.signum() * corner(x.abs(), y.abs(), 1.0);
                }
            }
            let e = e.abs() as f32;
            let o = Vec3::new(px as f32, py as f32, 0.5);
            let hit = intersect(&ctx, o, -Vec3::Z).expect("the floor");
            let bsdf = Bsdf::Diffuse(Diffuse {
                reflectance: Rgb::splat(0.5),
            });
            let view = hit.frame.to_local(Vec3::Z);
            for light_samples in [2, 8] {
                let share = LightShare::of_sample(light_samples, 0, 1, ([3, 5], 9));
                let mut sampler = Sampler::new(1, 2, 3);
                let l = direct_light(&ctx, (share, true), &hit, &bsdf, view, &mut sampler);
                let exact = Rgb::new(4.0, 3.0, 2.0) * (0.5 * std::f32::consts::FRAC_1_PI * e);
                if under {
                    let rel = ((l - exact) / exact).abs().max_element();
                    assert!(
                        rel < 1e-5,
                        "at {at:?}, {light_samples} samples: {l} vs {exact}"
                    );
                } else {
                    assert_eq!(l, Rgb::ZERO, "at {at:?}");
                }
            }
        }
    }

    /// Beside an area light, a point and a directional light each come in once and exactly,
    /// whatever the light samples: on the floor where the blocker hides the square, the
    /// direct light is ρ/π times their irradiance (I cos θ / d² and E cos θ) for any count of
    /// samples and any seed. Drawn among the samples by power, as before, the point light took
    /// 3 or 4 of 8 samples from one seed to the next and the image was speckled by that much.
    #[test]
    fn delta_lights_beside_an_area_light_are_exact_whatever_the_samples() {
        let mut scene = floor_under_a_light();
        let point = Vec3::new(4.0, 0.5, 1.0);
        let intensity = Rgb::new(0.8, 0.6, 0.4);
        let sun = Vec3::new(0.3, 0.0, -1.0).normalize();
        let irradiance = Rgb::new(0.2, 0.3, 0.5);
        scene.lights = vec![
            crate::scene::PunctualLight {
                name: "bulb".into(),
                kind: crate::scene::LightKind::Point,
                position: point,
                direction: -Vec3::Z,
                intensity,
            },
            crate::scene::PunctualLight {
                name: "sun".into(),
                kind: crate::scene::LightKind::Directional,
                position: Vec3::ZERO,
                direction: sun,
                intensity: irradiance,
            },
        ];
        let ctx = Tracer::new(&scene);
        let at = Vec3::new(3.5, 0.2, 0.0);
        let hit = intersect(&ctx, at + Vec3::Z * 0.1, -Vec3::Z).expect("the floor");
        let bsdf = Bsdf::Diffuse(Diffuse {
            reflectance: Rgb::splat(0.5),
        });
        let view = hit.frame.to_local(Vec3::Z);
        let to_point = point - at;
        let exact = (intensity * (to_point.z / to_point.length()) / to_point.length_squared()
            + irradiance * -sun.z)
            * (0.5 * std::f32::consts::FRAC_1_PI);
        for light_samples in [2, 8, 32] {
            for seed in 0..8 {
                let share = LightShare::of_sample(light_samples, 0, 1, ([3, seed], 9));
                let mut sampler = Sampler::new(seed as u64, 2, 3);
                let l = direct_light(&ctx, (share, true), &hit, &bsdf, view, &mut sampler);
                let rel = ((l - exact) / exact).abs().max_element();
                assert!(
                    rel < 1e-5,
                    "{light_samples} samples, seed {seed}: {l} vs {exact}"
                );
            }
        }
    }

    /// A pixel's camera samples share its light points out: their blocks are the first
    /// `total` points of the pixel's sequence, each once, in an order that differs between
    /// pixels, and every sample takes at least [`LightShare::LEAST`] (or all there are).
    #[test]
    fn a_pixels_samples_take_its_light_points_once_each() {
        for light_samples in [1, 2, 3, 32] {
            for samples in [1, 4, 16, 64] {
                let mut orders = Vec::new();
                for shuffle in [7u32, 0x9e37_79b9] {
                    let shares: Vec<LightShare> = (0..samples)
                        .map(|s| {
                            LightShare::of_sample(light_samples, s, samples, ([1, 2], shuffle))
                        })
                        .collect();
                    let total = takes_each_point_once(&shares, light_samples);
                    assert!(total >= light_samples);
                    assert_eq!(shares[0].scramble, [1, 2]);
                    orders.push(shares.iter().map(|s| s.first).collect::<Vec<_>>());
                }
                if samples > 1 {
                    assert_ne!(orders[0], orders[1], "{light_samples} over {samples}");
                }
            }
        }
    }
}
