//! Bounces of indirect light in the cache (spec §8.1, §8.4–§8.5; DESIGN.md §5.7–§5.8).
//!
//! Each bounce gathers, for every surfel, the light the previous bounce left in the tree (the
//! direct light for the first) through a microbuffer around its normal (spherical for
//! `roughdielectric`), and turns it into outgoing radiance: diffuse surfels by the cosine
//! convolution (one RGB value), the others through their BSDF's 4D Haar operator
//! ([`BsdfOperator`]), resampled from the local grid onto the surfel's global sphere map. The
//! result is added to the surfels' total radiance and becomes what the next bounce sends
//! (spec §8.5's recommendation: `emit` and `total` kept apart, never re-sending the total).
//!
//! Bounce control: the energy of a bounce is Σ area × luminance of the surfels' mean outgoing
//! radiance. The loop stops when a bounce carries less than `tolerance` of the reflected
//! total, or at `max`; once the ratio r of successive bounce energies has settled (three
//! bounces within 1 % of each other) and the remaining tail is still above the tolerance, the
//! geometric tail Σ_{j≥1} rʲ of the last bounce is added at once (a stiff scene, albedo near
//! 1, would need hundreds of bounces).
//!
//! Receivers gather per group of the view tree (spec §8.3, [`super::view_tree`]): nearby
//! surfels share one cut of the far senders. Every pixel of a bounce's microbuffer whose
//! centre ray hits the scene is normalised to full coverage ([`Microbuffer::close_gaps`]): the splats' coverage is right on average but not
//! pixel by pixel, and a bounce that lost a few percent of coverage would pass that loss on
//! to every further bounce (inside a closed room of radiance 1 the gather fell 3 % short).
//! With that, the senders' exact radiance (see [`Senders::seen`]) and the operator's exact
//! flux ([`BsdfOperator::outgoing`]), a closed room gathers π to 1e-4 and the white furnaces
//! of tests/furnace.rs hold to 0.2 % (diffuse) and 1.2 % (conductor, ρ = 0.99).

use super::bsdf_operator::BsdfOperator;
use super::view_tree::{receiver_groups, ReceiverGroup, VIEW_EPS};
use crate::accel::Accel;
use crate::bake::coding::{encode, CodedTree};
use crate::bake::pipeline::{intensity_map, surfel_bsdf, Baked, Progress, SurfelRadiance};
use crate::bake::plan::map_levels;
use crate::bake::store::{BakedCache, SOLID};
use crate::bake::surfels::Surfel;
use crate::bsdf::Bsdf;
use crate::error::{Error, Result};
use crate::gather::cut::splat_cut;
use crate::gather::fpbgi::{cluster_cut, member_buffer, ClusterReceivers};
use crate::gather::microbuffer::Microbuffer;
use crate::gather::senders::Senders;
use crate::geometry::frame::Frame;
use crate::geometry::offset::offset_origin;
use crate::haar::{texel_directions, Haar2d, SparseHaar};
use crate::scene::Scene;
use crate::spectrum::{luminance, Rgb};
use glam::{Vec3, Vec3A};
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

/// Microbuffer pixels per side for diffuse surfels (as the final render's default).
pub const DIFFUSE_BUFFER: u32 = 16;

/// Incoming coefficients below this fraction of their norm are dropped before D = V·C.
pub const INCOMING_TAU: f32 = 1e-3;

/// How many bounces to run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BounceSettings {
    /// The most explicit bounces.
    pub max: u32,
    /// Stop when a bounce carries less than this fraction of the reflected total; 0 runs
    /// exactly `max` bounces without extrapolation.
    pub tolerance: f32,
    /// The most of its L2 norm each column of a BSDF operator may lose to thresholding.
    pub operator_tau: f32,
    /// Share the far part of the gather among nearby surfels (the view tree, see
    /// [`super::view_tree`]); otherwise every surfel traverses the whole tree.
    pub view_tree: bool,
}

impl BounceSettings {
    /// `auto`: up to 30 bounces, stopping at 0.1 % of the total.
    pub fn auto() -> Self {
        BounceSettings {
            max: 30,
            tolerance: 1e-3,
            operator_tau: 1e-2,
            view_tree: true,
        }
    }

    /// Exactly `n` bounces.
    pub fn exactly(n: u32) -> Self {
        BounceSettings {
            max: n,
            tolerance: 0.0,
            ..Self::auto()
        }
    }
}

/// What the bounces did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BounceReport {
    /// Explicit bounces run.
    pub bounces: u32,
    /// Energy of each bounce (Σ area × luminance).
    pub energies: Vec<f64>,
    /// The last bounce's energy over the reflected total (direct and bounces).
    pub residual: f64,
    /// The geometric tail factor r/(1 − r) added, if any.
    pub extrapolated: Option<f64>,
    /// Seconds per bounce.
    pub seconds: Vec<f64>,
}

impl BounceReport {
    /// What the cache records (no times: the cache is byte-identical from run to run).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "bounces": self.bounces,
            "energies": self.energies,
            "residual": self.residual,
            "extrapolated_tail": self.extrapolated,
        })
    }
}

/// The energy measure of a set of surfel radiances: Σ area × luminance of the mean outgoing
/// radiance (over the front hemisphere for diffuse surfels, the sphere for maps).
fn energy(baked: &Baked, radiance: &[SurfelRadiance]) -> f64 {
    baked
        .surfels
        .iter()
        .zip(radiance)
        .map(|(s, r)| {
            let mean = match r {
                SurfelRadiance::Rgb(c) => *c,
                SurfelRadiance::Map(m) => m.mean(),
            };
            f64::from(s.area) * f64::from(luminance(mean))
        })
        .sum()
}

/// `a + b·k`, surfel by surfel (both of the same kind per surfel).
fn add_scaled(a: &SurfelRadiance, b: &SurfelRadiance, k: f32, tau: f32) -> SurfelRadiance {
    match (a, b) {
        (SurfelRadiance::Rgb(x), SurfelRadiance::Rgb(y)) => SurfelRadiance::Rgb(*x + *y * k),
        (SurfelRadiance::Map(x), SurfelRadiance::Map(y)) => SurfelRadiance::Map(
            SparseHaar::compress(&Haar2d::combine(&x.to_dense(), 1.0, &y.to_dense(), k), tau),
        ),
        // Surfels keep their kind from the direct light on; nothing else is produced.
        _ => a.clone(),
    }
}

/// The BSDF operators of a bake, one per distinct BSDF (built on first use).
struct Operators {
    built: Vec<(Bsdf, Arc<BsdfOperator>)>,
}

impl Operators {
    fn get(&mut self, bsdf: &Bsdf, tau: f32) -> Arc<BsdfOperator> {
        if let Some((_, op)) = self.built.iter().find(|(b, _)| b == bsdf) {
            return op.clone();
        }
        let n = operator_side(bsdf);
        let op = Arc::new(BsdfOperator::new(bsdf, n, tau));
        self.built.push((*bsdf, op.clone()));
        op
    }
}

/// The operator grid for a BSDF: fine enough for its lobe, as the surfel maps' resolution.
pub fn operator_side(bsdf: &Bsdf) -> u32 {
    match bsdf.alpha() {
        Some(a) if a < 0.08 => 32,
        Some(a) if a < 0.3 => 16,
        _ => 8,
    }
}

/// Run the bounces on `baked` (direct light done and coded): its surfels' radiance becomes the
/// total and its tree is coded again.
pub fn add_bounces(
    scene: &Scene,
    baked: &mut Baked,
    settings: &BounceSettings,
    progress: Progress,
    cancel: &AtomicBool,
) -> Result<BounceReport> {
    let mut report = BounceReport::default();
    if settings.max == 0 || baked.surfels.is_empty() {
        return Ok(report);
    }
    let tau = baked.settings.tau;
    let accel = Accel::build(scene);
    let bsdfs: Vec<Bsdf> = baked
        .surfels
        .iter()
        .map(|s| surfel_bsdf(scene, s))
        .collect();
    let mut operators = Operators { built: Vec::new() };
    let ops: Vec<Option<Arc<BsdfOperator>>> = bsdfs
        .iter()
        .map(|b| (!matches!(b, Bsdf::Diffuse(_))).then(|| operators.get(b, settings.operator_tau)))
        .collect();
    let reflected_direct: Vec<SurfelRadiance> = baked
        .radiance
        .iter()
        .zip(&baked.emitted)
        .map(|(r, e)| add_scaled(r, &SurfelRadiance::Rgb(*e), -1.0, tau))
        .collect();
    let mut total_energy = energy(baked, &reflected_direct);
    let mut emit: Option<Vec<SurfelRadiance>> = None;
    let mut ratios: Vec<f64> = Vec::new();
    for bounce in 1..=settings.max {
        let start = std::time::Instant::now();
        let done_before = (bounce - 1) as f32 / settings.max as f32;
        progress("bounces", done_before);
        let senders = senders_of(baked, emit.take())?;
        let light = gather_bounce(
            (scene, &accel),
            &senders,
            baked,
            (&bsdfs, &ops),
            settings.view_tree,
            (
                &|f| progress("bounces", done_before + f / settings.max as f32),
                cancel,
            ),
        )?;
        let e = energy(baked, &light);
        report.energies.push(e);
        if let Some(&prev) = report.energies.iter().rev().nth(1) {
            ratios.push(if prev > 0.0 { e / prev } else { 0.0 });
        }
        for (t, l) in baked.radiance.iter_mut().zip(&light) {
            *t = add_scaled(t, l, 1.0, tau);
        }
        total_energy += e;
        report.bounces = bounce;
        report.seconds.push(start.elapsed().as_secs_f64());
        report.residual = if total_energy > 0.0 {
            e / total_energy
        } else {
            0.0
        };
        let fixed_count = settings.tolerance <= 0.0;
        if !fixed_count && report.residual < f64::from(settings.tolerance) {
            break;
        }
        let settled = ratios.len() >= 3 && {
            let last = &ratios[ratios.len() - 3..];
            let (lo, hi) = last.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &r| {
                (lo.min(r), hi.max(r))
            });
            hi < 1.0 && hi - lo <= 0.01 * hi
        };
        if !fixed_count && (settled || bounce == settings.max) {
            let r = *ratios.last().unwrap_or(&0.0);
            if r > 0.0 && r < 1.0 {
                let tail = r / (1.0 - r);
                for (t, l) in baked.radiance.iter_mut().zip(&light) {
                    *t = add_scaled(t, l, tail as f32, tau);
                }
                report.extrapolated = Some(tail);
                report.residual = e * tail / (total_energy + e * tail);
            }
            break;
        }
        emit = Some(light);
    }
    progress("bounces", 1.0);
    baked.coded = coded_for(baked);
    baked.plan.json["bounces"] = report.to_json();
    Ok(report)
}

/// The tree of `baked` coded for its surfels' radiance.
fn coded_for(baked: &Baked) -> CodedTree<Rgb> {
    let levels = baked.plan.map_levels;
    let leaf = |i: u32| {
        let s = &baked.surfels[i as usize];
        let back = baked.mesh_flags[s.mesh as usize] & SOLID == 0;
        intensity_map(s, &baked.radiance[i as usize], levels, back)
    };
    encode(
        &baked.tree,
        &leaf,
        baked.coded.split_level,
        baked.settings.tau,
    )
}

/// The senders of `baked`'s tree with the surfels sending `emit` (their total radiance, less
/// emission, when `None`).
fn senders_of(baked: &mut Baked, emit: Option<Vec<SurfelRadiance>>) -> Result<Senders> {
    let path = Path::new("(the previous bounce, in memory)");
    let Some(emit) = emit else {
        return Ok(Senders::from_cache(&BakedCache::in_memory(path, baked)?)?);
    };
    // Swap the bounce's light in (no emission: it was sent by the direct light already),
    // read it as a cache, and swap the total back.
    let total = std::mem::replace(&mut baked.radiance, emit);
    let emitted = std::mem::replace(&mut baked.emitted, vec![Rgb::ZERO; baked.surfels.len()]);
    let emit_coded = coded_for(baked);
    let coded = std::mem::replace(&mut baked.coded, emit_coded);
    let cache = BakedCache::in_memory(path, baked);
    baked.radiance = total;
    baked.emitted = emitted;
    baked.coded = coded;
    Ok(Senders::from_cache(&cache?)?)
}

/// What the ray through the centre of each pixel `k` of `mb` for which `wanted(k)` holds,
/// from surfel `s`, hits first: the point, its mesh and geometric normal (`None` for a miss
/// or a pixel not wanted).
pub fn pixel_hits(
    accel: &Accel,
    scene: &Scene,
    s: &Surfel,
    mb: &Microbuffer,
    wanted: impl Fn(usize) -> bool,
) -> Vec<Option<PixelHit>> {
    let (p, err) = s.position_with_error(scene);
    let ng = Vec3A::from(s.n);
    mb.pixels
        .iter()
        .enumerate()
        .map(|(k, px)| {
            if !wanted(k) {
                return None;
            }
            let w = mb.frame.to_world(px.dir);
            let origin = Vec3::from(offset_origin(p, err, ng, Vec3A::from(w)));
            accel.closest_hit(origin, w, 0.0, f32::INFINITY).map(|h| {
                let hm = &scene.meshes[h.mesh as usize];
                let [a, b, c] = hm.triangles[h.triangle as usize].map(|k| hm.positions[k as usize]);
                PixelHit {
                    point: origin + w * h.t,
                    mesh: h.mesh,
                    normal: (b - a).cross(c - a).normalize_or_zero(),
                }
            })
        })
        .collect()
}

/// What a pixel's centre ray hit.
#[derive(Clone, Copy, Debug)]
pub struct PixelHit {
    pub point: Vec3,
    pub mesh: u32,
    /// The hit triangle's geometric normal (its front face).
    pub normal: Vec3,
}

/// Close the gaps of a bounce's buffer: pixels whose ray hits the scene are normalised to full
/// coverage, and those no splat reached (between the discs of a surface a few millimetres
/// away, which leave holes there: a receiver 1 mm from a wall saw 112 of its 256 pixels
/// empty) take the light of the surfel nearest the hit point, on the hit mesh and facing the
/// same way. Pixels the splats cover fully are closed without a ray (in a closed room, most:
/// the rays were half a bounce's time).
pub fn close_buffer(
    senders: &Senders,
    (accel, scene): (&Accel, &Scene),
    s: &Surfel,
    mb: &mut Microbuffer,
) {
    let covered = |alpha: f32| alpha >= 1.0;
    let hits = pixel_hits(accel, scene, s, mb, |k| !covered(mb.alpha[k]));
    let closed: Vec<bool> = (0..hits.len())
        .map(|k| covered(mb.alpha[k]) || hits[k].is_some())
        .collect();
    mb.close_gaps(|k| closed[k]);
    for (k, hit) in hits.iter().enumerate() {
        let Some(h) = hit else { continue };
        if mb.alpha[k] > 0.0 {
            continue;
        }
        let nearest = senders.nearest_surfel(h.point, |r| {
            r.mesh == h.mesh && Vec3::from(r.n).dot(h.normal) > 0.5
        });
        if let Some(i) = nearest {
            let towards = mb.frame.to_world(-mb.pixels[k].dir);
            let cos = Vec3::from(senders.surfels[i as usize].n).dot(towards);
            mb.fill_pixel(k, senders.surfel_radiance(i, towards, cos, s.mesh));
        }
    }
}

/// One bounce: every surfel's outgoing radiance from the light `senders` send it, per receiver
/// group of the view tree or per surfel.
fn gather_bounce(
    (scene, accel): (&Scene, &Accel),
    senders: &Senders,
    baked: &Baked,
    (bsdfs, ops): (&[Bsdf], &[Option<Arc<BsdfOperator>>]),
    view_tree: bool,
    (progress, cancel): (&(dyn Fn(f32) + Sync), &AtomicBool),
) -> Result<Vec<SurfelRadiance>> {
    let groups = if view_tree {
        receiver_groups(&baked.tree, &baked.surfels)
    } else {
        (0..baked.surfels.len() as u32)
            .map(|i| ReceiverGroup {
                members: vec![i],
                active: i,
                radius: 0.0,
                cone: 0.0,
            })
            .collect()
    };
    let side = |i: u32| ops[i as usize].as_ref().map_or(DIFFUSE_BUFFER, |op| op.n);
    let tau = baked.settings.tau;
    let done = AtomicUsize::new(0);
    let gathered: Vec<Vec<(u32, SurfelRadiance)>> = groups
        .par_iter()
        .map_init(Vec::new, |stack, group| {
            if cancel.load(Ordering::Relaxed) {
                return Vec::new();
            }
            let n = done.fetch_add(1, Ordering::Relaxed) + 1;
            if n.is_multiple_of(256) {
                progress(n as f32 / groups.len() as f32);
            }
            let buffer = |i: u32| {
                let s = &baked.surfels[i as usize];
                let spherical = bsdfs[i as usize].is_two_sided();
                Microbuffer::new(side(i), spherical, Frame::from_normal(s.n))
            };
            let outgoing = |i: u32, mut mb: Microbuffer| {
                let s = &baked.surfels[i as usize];
                close_buffer(senders, (accel, scene), s, &mut mb);
                (
                    i,
                    surfel_outgoing(&mb, &bsdfs[i as usize], &ops[i as usize], tau),
                )
            };
            if let [i] = group.members[..] {
                let s = &baked.surfels[i as usize];
                let mut mb = buffer(i);
                splat_cut(senders, s.p, s.mesh, &mut mb, &[0], stack);
                mb.resolve();
                return vec![outgoing(i, mb)];
            }
            let a = &baked.surfels[group.active as usize];
            let spherical = bsdfs[group.active as usize].is_two_sided();
            let receivers = ClusterReceivers {
                p: a.p,
                mesh: a.mesh,
                frame: Frame::from_normal(a.n),
                radius: group.radius,
                plane_slope: (!spherical).then(|| group.cone.sin()),
            };
            let n = group
                .members
                .iter()
                .map(|&i| side(i))
                .max()
                .unwrap_or(DIFFUSE_BUFFER);
            let mut cut = cluster_cut(senders, &receivers, VIEW_EPS, n);

            group
                .members
                .iter()
                .map(|&i| {
                    let s = &baked.surfels[i as usize];
                    let mut mb = buffer(i);
                    member_buffer(senders, &mut cut, s.p, s.mesh, &mut mb, stack);
                    outgoing(i, mb)
                })
                .collect()
        })
        .collect();
    if cancel.load(Ordering::Relaxed) {
        return Err(Error::Cancelled);
    }
    let mut light = vec![SurfelRadiance::Rgb(Rgb::ZERO); baked.surfels.len()];
    for (i, l) in gathered.into_iter().flatten() {
        light[i as usize] = l;
    }
    Ok(light)
}

/// A surfel's outgoing radiance from its closed buffer: the cosine convolution for diffuse
/// surfels (one RGB value), D = V·C resampled onto its sphere map for the others.
fn surfel_outgoing(
    mb: &Microbuffer,
    bsdf: &Bsdf,
    op: &Option<Arc<BsdfOperator>>,
    tau: f32,
) -> SurfelRadiance {
    match op {
        None => SurfelRadiance::Rgb(mb.convolve(bsdf, Vec3::Z)),
        Some(op) => {
            let local = op.outgoing(&mb.radiance, INCOMING_TAU);
            SurfelRadiance::Map(resample(
                &local,
                op,
                mb.frame,
                map_levels(bsdf).unwrap_or(3),
                tau,
            ))
        }
    }
}

/// The surfel's global sphere map (2^levels texels per side) of its outgoing radiance on the
/// operator's local grid, by nearest texel (spec §8.2: "the filter is unspecified").
fn resample(
    local: &[Rgb],
    op: &BsdfOperator,
    frame: Frame,
    levels: u32,
    tau: f32,
) -> SparseHaar<Rgb> {
    let texels: Vec<Rgb> = texel_directions(levels)
        .iter()
        .map(|&w| {
            op.texel_of(frame.to_local(w))
                .map_or(Rgb::ZERO, |t| local[t as usize])
        })
        .collect();
    SparseHaar::compress(&Haar2d::forward(&texels, 1 << levels), tau)
}
