//! Bounces of indirect light in the cache (docs/method.md §8.1, §8.4–§8.5; docs/design.md §5.7–§5.8).
//!
//! Each bounce gathers, for every surfel, the light the previous bounce left in the tree (the
//! direct light for the first) through a microbuffer around its normal (spherical for
//! `roughdielectric`), and turns it into outgoing radiance: diffuse surfels by the cosine
//! convolution (one RGB value), the others through their BSDF's 4D Haar operator
//! ([`BsdfOperator`](super::BsdfOperator)), resampled from the local grid onto the surfel's
//! global sphere map. The result becomes what the next bounce sends (docs/method.md §8.5's
//! recommendation: `emit` and `total` kept apart, never re-sending the total), thresholded at
//! [`SENT_TAU_FACTOR`] times the cache's threshold with its flux kept. What the receivers
//! gather is linear in the light sent, so it is summed over the bounces (`Incident`) and
//! turned into outgoing radiance, blended and added to the total once, at the end, at the
//! cache's threshold.
//!
//! Bounce control: the energy of a bounce is Σ area × luminance of the surfels' mean outgoing
//! radiance. The loop stops when a bounce carries less than `tolerance` of the reflected
//! total, when the ratio r of successive bounce energies has settled (three bounces within
//! 1 % of each other), or at `max`; whichever stops it, the geometric tail Σ_{j≥1} rʲ of the
//! last bounce is added at once, r each channel's own ratio (a stiff scene, albedo near 1, would need hundreds of
//! bounces, and a tail left out darkens the cache by r/(1 − r) times the last bounce).
//!
//! Receivers gather per group of the view tree (docs/method.md §8.3, [`super::view_tree`]): nearby
//! surfels share one cut of the far senders. Every pixel of a bounce's microbuffer whose
//! centre ray hits the scene is normalised to full coverage ([`Microbuffer::close_gaps`]): the splats' coverage is right on average but not
//! pixel by pixel, and a bounce that lost a few percent of coverage would pass that loss on
//! to every further bounce (inside a closed room of radiance 1 the gather fell 3 % short).
//! With that, the senders' exact radiance (see [`Senders::seen`]) and the operator's exact
//! flux ([`BsdfOperator::outgoing`](super::BsdfOperator::outgoing)), a closed room gathers π to 1e-4 and the white furnaces
//! of tests/furnace.rs hold to 0.5 % (diffuse) and 0.5 % (conductor, ρ = 0.99).
//!
//! A diffuse receiver's pixel that holds more than one surface (an occluder in front of what
//! it hides, a node whose surfels face many ways) is traced instead, 9 rays through equal
//! parts of it (`trace_mixed_pixels`): coverages composite a pixel as a whole, which missed
//! a small lamp hiding the brightest part of its own spot on the ceiling. A directional
//! receiver's mixed pixels are traced where they border its horizon.
//!
//! The gather is geometry alone, so it runs once: the first bounce records, per receiver, its
//! closed buffer as weighted links to the senders' lookups ([`super::transport`]), and every
//! bounce evaluates those links against the light the previous one left. Links past the
//! memory budget ([`BounceSettings::transport_budget`]) are gathered again in every bounce by
//! the same code, so the cache does not depend on the budget.

use super::bsdf_operator::SurfelOperator;
use super::kept::{KeptTransport, TransportHandoff, TransportKey};
use super::receivers::Receivers;
use super::report::{BounceReport, TransportReport};
use super::settings::{default_transport_budget, BounceSettings};
use super::transport::{read_nodes, slot_values, LinkScratch, ReceiverLinks, SlotIndex, Slots};
use super::view_tree::{receiver_groups, GROUP_SURFELS, VIEW_EPS};
use crate::accel::Accel;
use crate::bake::baked::Baked;
use crate::bake::store::records_of;
use crate::bsdf::Bsdf;
use crate::cache::store::geometry_hash;
use crate::error::{Error, Result};
use crate::gather::fpbgi::{Cluster, ClusterGather, ClusterReceivers};
use crate::gather::microbuffer::Microbuffer;
use crate::gather::senders::Senders;
use crate::geometry::frame::Frame;
use crate::geometry::offset::offset_origin;
use crate::haar::{texel_directions, Haar2d, SparseHaar};
use crate::progress::Progress;
use crate::scene::Scene;
use crate::spectrum::{Rgb, LUMINANCE};
use crate::surfels::coding::{encode, node_sums, CodedTree};
use crate::surfels::radiance::{intensity_of, map_levels, SurfelRadiance};
use crate::surfels::Surfel;
use glam::{DVec3, Vec3, Vec3A};
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// The threshold of the light the bounces send one another, over the cache's threshold: what
/// a bounce leaves is gathered again and averaged over many senders and pixels, so it need not
/// be kept as finely as the light the cache stores (whose maps are made once, at the end, from
/// what the receivers gathered over all the bounces at the cache's own threshold). At 5× (1e-2
/// for the default 2e-3) the final 256² images of the five Cornell-class scenes move by a
/// relMSE of 1.1e-6 to 6.1e-6, a thousandth of their error against Mitsuba (2.2e-3 to
/// 6.4e-3); the mirror box's bounce light keeps 2.2 million coefficients instead of 7.3, and
/// a later bounce costs 0.75 s instead of 1.2 (docs/bounces.md).
pub const SENT_TAU_FACTOR: f32 = 5.0;

/// The energy of a set of surfel radiances per channel: Σ area × the mean outgoing radiance
/// (over the front hemisphere for diffuse surfels, the sphere for maps), red, green, blue.
fn channel_energies(baked: &Baked, radiance: &[SurfelRadiance]) -> DVec3 {
    baked
        .surfels
        .iter()
        .zip(radiance)
        .fold(DVec3::ZERO, |sum, (s, l)| {
            let mean = match l {
                SurfelRadiance::Rgb(c) => *c,
                SurfelRadiance::Map(m) => m.mean(),
            };
            sum + f64::from(s.area) * mean.as_dvec3()
        })
}

/// The energy measure of the bounce control: the luminance of [`channel_energies`].
fn energy_of(channels: DVec3) -> f64 {
    DVec3::from(LUMINANCE.map(f64::from)).dot(channels)
}

/// The geometric tail Σ_{j≥1} rʲ = r/(1 − r) of a channel whose last two bounces carried
/// `prev` and `last`: none where the light does not shrink from bounce to bounce.
fn tail_of(prev: f64, last: f64) -> f64 {
    let r = if prev > 0.0 { last / prev } else { 0.0 };
    if r > 0.0 && r < 1.0 {
        r / (1.0 - r)
    } else {
        0.0
    }
}

/// `a + b·k`, surfel by surfel (both of the same kind per surfel).
fn add_scaled(a: &SurfelRadiance, b: &SurfelRadiance, k: f32, tau: f32) -> SurfelRadiance {
    match (a, b) {
        (SurfelRadiance::Rgb(x), SurfelRadiance::Rgb(y)) => SurfelRadiance::Rgb(*x + *y * k),
        (SurfelRadiance::Map(x), SurfelRadiance::Map(y)) => {
            SurfelRadiance::Map(SparseHaar::weighted_sum(&[(x, 1.0), (y, k)], tau))
        }
        // Surfels keep their kind from the direct light on; nothing else is produced.
        _ => a.clone(),
    }
}

/// Receiver groups recorded at once: enough to keep both cores busy, few enough that the
/// links of groups past the budget never pile up.
const RECORD_CHUNK: usize = 512;

/// Run the bounces on `baked` (direct light done and coded): its surfels' radiance becomes the
/// total and its tree is coded again.
pub fn add_bounces(
    scene: &Scene,
    baked: &mut Baked,
    settings: &BounceSettings,
    progress: Progress,
    cancel: &AtomicBool,
    handoff: &mut TransportHandoff,
) -> Result<BounceReport> {
    let mut report = BounceReport::default();
    if settings.max == 0 || baked.surfels.is_empty() {
        return Ok(report);
    }
    // The first bounce's time includes recording the transport.
    let mut start = std::time::Instant::now();
    let tau = baked.settings.tau;
    let bsdfs = &baked.bsdfs;
    // Diffuse surfels store RGB; every other one a map, through its BSDF's operator.
    let ops = baked.operators.of_each(bsdfs, settings.operator_tau, |b| {
        !matches!(b, Bsdf::Diffuse(_))
    });
    let reflected_direct: Vec<SurfelRadiance> = baked
        .radiance
        .iter()
        .zip(&baked.emitted)
        .zip(&baked.surfels)
        .map(|((r, e), s)| without_emission(r, *e, s.n, tau))
        .collect();
    let kinds: Vec<Option<u32>> = ops
        .iter()
        .zip(bsdfs)
        .map(|(op, b)| op.as_ref().and_then(|_| map_levels(b)))
        .collect();
    let receivers = Receivers::choose(
        &baked.tree,
        &baked.surfels,
        &kinds,
        settings.receiver_stride,
    );
    let groups = if settings.view_tree {
        receiver_groups(&baked.tree, &baked.surfels)
    } else {
        (0..baked.surfels.len() as u32)
            .map(|i| Cluster {
                members: vec![i],
                active: i,
                radius: 0.0,
                cone: Some(0.0),
            })
            .collect()
    };
    let groups = receivers.groups(groups, &baked.surfels);
    let slots =
        Slots::new(&baked.tree, &baked.radiance, baked.plan.map_levels).map_err(|too_many| {
            Error::InvalidSetting(format!(
                "the bounces would read {} values of the tree, more than 2^32; bake fewer \
             points (--points) or rougher materials",
                too_many.0
            ))
        })?;
    // The first bounce records every group's links, keeping them in group order while they
    // fit the budget.
    // The receivers' summed incident light (and one bounce's beside it) is held whatever the
    // budget: the links get what it leaves.
    let incident_bytes: u64 = (0..baked.surfels.len())
        .filter(|&i| receivers.gathers(i as u32))
        .filter_map(|i| ops[i].as_ref())
        .map(|op| 2 * (op.shared.size() * size_of::<Rgb>()) as u64)
        .sum();
    let budget = settings
        .transport_budget
        .unwrap_or_else(default_transport_budget)
        .saturating_sub(incident_bytes);
    // The key is hashed only where a transport is handed in or asked for.
    let key = (handoff.keep || handoff.reuse.is_some())
        .then(|| transport_key(scene, baked, &ops, &kinds, &slots));
    let reused = handoff.reuse.take().zip(key).and_then(|(t, key)| {
        let checked = t.check(&key, &slots, &groups, |l, read| {
            let i = l.surfel as usize;
            let directional = ops[i].as_ref().map(|op| {
                let levels = map_levels(&bsdfs[i]).unwrap_or(3);
                (op.shared.size(), 1usize << (2 * levels))
            });
            l.check(directional, read)
        });
        match checked {
            Ok(()) => Some(t),
            Err(why) => {
                handoff.refused = Some(why);
                None
            }
        }
    });
    handoff.replayed = reused.is_some();
    // The gather's geometry (the scene's rays and the tree as senders, read once from the
    // bake in memory; the radiance each bounce sends comes from the transport's slots) is
    // built only where some group gathers: not for a replay that holds every group's links
    // (the senders alone were 0.36 s of cbox-rough's 3 s relight).
    let geometry = match &reused {
        Some(t) if t.kept.len() == groups.len() => None,
        _ => Some(GatherGeometry {
            accel: Accel::build(scene),
            senders: geometry_senders(baked)?,
        }),
    };
    let gather = Gather {
        scene,
        geometry: geometry.as_ref(),
        surfels: &baked.surfels,
        tau,
        sent_tau: tau * SENT_TAU_FACTOR,
        bsdfs,
        normals: &baked.shading_normals,
        ops: &ops,
        slots: &slots,
    };
    let (index, kept, transport) = match reused {
        Some(t) => (SlotIndex::from_words(t.words), t.kept, t.report),
        None => record_transport(
            &gather,
            &groups,
            (&slots, &receivers),
            budget,
            incident_bytes,
            (settings.max, progress, cancel),
        )?,
    };
    report.transport = transport;
    let regathered = &groups[kept.len()..];
    let read = read_nodes(&slots, &index, &baked.tree);

    let mut total_energy = energy_of(channel_energies(baked, &reflected_direct));
    // The last two bounces' energies per channel, for the tail.
    let mut channels = [DVec3::ZERO; 2];
    // What the receivers gathered over the bounces, summed before their BSDFs: the bounces'
    // light is turned into outgoing radiance and added to the total once, at the end.
    let mut gathered = vec![Incident::Nothing; baked.surfels.len()];
    // What the next bounce sends: the reflected direct light, then each bounce's light.
    let mut emit: Vec<SurfelRadiance> = reflected_direct;
    let mut ratios: Vec<f64> = Vec::new();
    // The light each read slot holds, refilled every bounce.
    let mut values = Vec::new();
    for bounce in 1..=settings.max {
        let done_before = (bounce - 1) as f32 / settings.max as f32;
        // The light sent is read once, into the slots, and dropped before the new light is
        // made: the heap reuses its memory (fresh pages are cleared by the kernel).
        {
            let sent = std::mem::take(&mut emit);
            fill_slots(baked, (&slots, &index, &read), &sent, &mut values);
        }
        let (mut light, incident) = gather.evaluate(&kept, regathered, &index, &values, cancel)?;
        receivers.blend(&mut light, tau);
        gather.reflect(&mut light);
        channels = [channels[1], channel_energies(baked, &light)];
        let e = energy_of(channels[1]);
        report.energies.push(e);
        if let Some(&prev) = report.energies.iter().rev().nth(1) {
            ratios.push(if prev > 0.0 { e / prev } else { 0.0 });
        }
        total_energy += e;
        report.bounces = bounce;
        report.residual = if total_energy > 0.0 {
            e / total_energy
        } else {
            0.0
        };
        let fixed_count = settings.tolerance <= 0.0;
        let settled = ratios.len() >= 3 && {
            let last = &ratios[ratios.len() - 3..];
            let (lo, hi) = last.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &r| {
                (lo.min(r), hi.max(r))
            });
            hi < 1.0 && hi - lo <= 0.01 * hi
        };
        let small = report.residual < f64::from(settings.tolerance);
        let stop = !fixed_count && (small || settled || bounce == settings.max);
        // On stopping, the bounces left sum to about this one times r/(1 − r), r the last
        // ratio of successive energies: added with it, whatever stopped the loop (left out,
        // they would darken the cache by that much). Per channel: a coloured room's channels
        // shrink at their own rates (red light between a red wall and gold keeps more of
        // itself each bounce than the room's luminance does), and one luminance ratio cut
        // the redder channel's tail short.
        let tail = stop.then(|| {
            let [prev, last] = channels;
            [0, 1, 2].map(|c| tail_of(prev[c], last[c]))
        });
        let tail = tail.filter(|t| t.iter().any(|&x| x > 0.0));
        let weight = Rgb::ONE + tail.map_or(Rgb::ZERO, |t| Rgb::from(t.map(|x| x as f32)));
        for (i, l) in incident {
            gathered[i as usize].add(l, weight);
        }
        if let Some(tail) = tail {
            report.extrapolated = Some(tail);
            let rest = energy_of(channels[1] * DVec3::from(tail));
            report.residual = rest / (total_energy + rest);
        }
        report.seconds.push(start.elapsed().as_secs_f64());
        start = std::time::Instant::now();
        progress("bounces", done_before + 1.0 / settings.max as f32);
        if stop {
            break;
        }
        emit = light;
    }
    let start = std::time::Instant::now();
    let mut light = gather.outgoing_of_all(&gathered, &kept);
    drop(gathered);
    receivers.blend(&mut light, tau);
    gather.reflect(&mut light);
    baked
        .radiance
        .par_iter_mut()
        .zip(&light)
        .for_each(|(t, l)| *t = add_scaled(t, l, 1.0, tau));
    baked.coded = coded_for(baked);
    if let Some(key) = key.filter(|_| handoff.keep) {
        handoff.kept = Some(KeptTransport {
            key,
            report: report.transport,
            words: index.words(),
            kept,
            operators: baked.operators.keyed(),
            direct: None,
        });
    }
    report.final_seconds = start.elapsed().as_secs_f64();
    progress("bounces", 1.0);
    baked.plan.json["bounces"] = report.to_json();
    Ok(report)
}

/// The first bounce's recording: every group's links, kept in group order while they fit
/// `budget` bytes (the groups past it gather again in every bounce), their slots compact, with
/// the index of the slots they read and the transport's size. `bounces` scales the progress
/// reported (the recording is most of the first of them).
fn record_transport(
    gather: &Gather,
    groups: &[Cluster],
    (slots, receivers): (&Slots, &Receivers),
    budget: u64,
    incident_bytes: u64,
    (bounces, progress, cancel): (u32, Progress, &AtomicBool),
) -> Result<(SlotIndex, Vec<Vec<ReceiverLinks>>, TransportReport)> {
    let mut index = SlotIndex::new(slots);
    let mut kept: Vec<Vec<ReceiverLinks>> = Vec::new();
    let mut transport = TransportReport {
        receivers: receivers.count(),
        slots: slots.total(),
        incident_bytes,
        ..TransportReport::default()
    };
    let mut full = false;
    for (c, chunk) in groups.chunks(RECORD_CHUNK).enumerate() {
        // The flag is looked at per group: a chunk takes up to a second or so.
        let recorded: Vec<Vec<ReceiverLinks>> = chunk
            .par_iter()
            .map_init(Scratch::default, |scratch, group| {
                if cancel.load(Ordering::Relaxed) {
                    return Vec::new();
                }
                let links = gather.record(group, scratch);
                for l in &links {
                    l.mark(&index);
                }
                links
            })
            .collect();
        if cancel.load(Ordering::Relaxed) {
            return Err(Error::Cancelled);
        }
        for links in recorded {
            let bytes: u64 = links.iter().map(|l| l.bytes() as u64).sum();
            transport.bytes_unbounded += bytes;
            full = full || transport.bytes + bytes > budget;
            if !full {
                transport.bytes += bytes;
                kept.push(links);
            }
        }
        let done = ((c + 1) * RECORD_CHUNK).min(groups.len()) as f32 / groups.len() as f32;
        progress("bounces", 0.9 * done / bounces as f32);
    }
    index.freeze();
    kept.par_iter_mut()
        .flatten()
        .for_each(|l| l.compact(&index));
    transport.kept_groups = kept.len();
    transport.regathered_groups = groups.len() - kept.len();
    transport.read_slots = index.len();
    Ok((index, kept, transport))
}

/// The hash of everything the transport of `baked`'s bounces depends on: the scene's
/// geometry and the bake's settings ([`geometry_hash`]: the rays that close the buffers' gaps
/// hit the triangles, the settings choose the receivers and their groups), the surfels (so
/// also the tree), their shading normals, each receiver's kind (its map's levels, its BSDF
/// operator's grid, whether it gathers spherically), the tree's map levels and the slots.
/// Reflectances, tints, transmittances and emission are not in it: they change no link.
fn transport_key(
    scene: &Scene,
    baked: &Baked,
    ops: &[Option<SurfelOperator>],
    kinds: &[Option<u32>],
    slots: &Slots,
) -> TransportKey {
    let receivers: Vec<[u32; 4]> = (0..baked.surfels.len())
        .map(|i| {
            let (side, hemispheres) = ops[i]
                .as_ref()
                .map_or((0, 0), |op| (op.shared.n, op.shared.hemispheres));
            let two_sided = u32::from(baked.bsdfs[i].is_two_sided());
            [side, hemispheres, two_sided, kinds[i].unwrap_or(u32::MAX)]
        })
        .collect();
    let mut h = xxhash_rust::xxh3::Xxh3::new();
    h.update(&super::kept::VERSION.to_le_bytes());
    h.update(&geometry_hash(scene, &baked.settings.to_json()));
    h.update(bytemuck::cast_slice(&baked.surfels));
    h.update(bytemuck::cast_slice(&baked.shading_normals));
    h.update(bytemuck::cast_slice(&receivers));
    h.update(&baked.plan.map_levels.to_le_bytes());
    h.update(&slots.total().to_le_bytes());
    h.digest128().to_le_bytes()
}

/// The tree of `baked` as senders of geometry alone ([`Senders::geometry_of`]), from its
/// records in memory: what the cache would hold, without encoding a byte.
fn geometry_senders(baked: &Baked) -> Result<Senders> {
    let (records, surfel_records) = records_of(baked);
    // A lookup reads only a surfel map's resolution: each map stands in as an empty one.
    let empty = SparseHaar::compress(&Haar2d::forward(&[Rgb::ZERO], 1), 0.0);
    let surfel_maps = baked
        .radiance
        .iter()
        .map(|r| match r {
            SurfelRadiance::Map(m) => Some(empty.clone().refined_to(m.levels())),
            SurfelRadiance::Rgb(_) => None,
        })
        .collect();
    let projected = &baked.projected.nodes;
    Ok(Senders::geometry_of(
        Path::new("(the bake in memory)"),
        &records,
        surfel_records,
        &baked.tree.order,
        [&|j| projected[j as usize].g.clone(), &|j| {
            projected[j as usize].h.clone()
        }],
        surfel_maps,
    )?)
}

/// A surfel's direct-lit radiance less its emission (on the front, where it leaves): the light
/// it reflects, which the first bounce sends.
fn without_emission(r: &SurfelRadiance, emitted: Rgb, n: Vec3, tau: f32) -> SurfelRadiance {
    if emitted == Rgb::ZERO {
        return r.clone();
    }
    match r {
        SurfelRadiance::Rgb(c) => SurfelRadiance::Rgb(*c - emitted),
        SurfelRadiance::Map(m) => {
            let levels = m.levels();
            let texels: Vec<Rgb> = m
                .to_dense()
                .inverse()
                .into_iter()
                .zip(texel_directions(levels))
                .map(|(l, w)| if w.dot(n) > 0.0 { l - emitted } else { l })
                .collect();
            SurfelRadiance::Map(SparseHaar::compress(
                &Haar2d::forward(&texels, 1 << levels),
                tau,
            ))
        }
    }
}

/// Fill `values` with what every read slot of `index` holds in the light `sent`: the exact
/// intensity of the inner nodes whose texels are `read` ([`node_sums`]), then the slots.
fn fill_slots(
    baked: &Baked,
    (slots, index, read): (&Slots, &SlotIndex, &[bool]),
    sent: &[SurfelRadiance],
    values: &mut Vec<Rgb>,
) {
    let leaf = intensity_of(&baked.surfels, &baked.mesh_flags, sent);
    let sums = node_sums(&baked.tree, &leaf, &|j| read[j as usize]);
    let tree = (&baked.tree, &sums[..]);
    slot_values(slots, index, tree, &baked.surfels, sent, values);
}

/// The tree of `baked` coded for its surfels' radiance.
fn coded_for(baked: &Baked) -> CodedTree<Rgb> {
    let leaf = intensity_of(&baked.surfels, &baked.mesh_flags, &baked.radiance);
    encode(
        &baked.tree,
        &leaf,
        baked.plan.map_levels,
        baked.coded.split_level,
        baked.settings.tau,
    )
}

/// What the ray through the centre of each pixel `k` of `mb` for which `wanted(k)` holds,
/// from surfel `s`, hits first: the point, its mesh and geometric normal (`None` for a miss
/// or a pixel not wanted).
pub(crate) fn pixel_hits(
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
                let [a, b, c] = h.corners.map(Vec3::from);
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
pub(crate) struct PixelHit {
    /// The hit point.
    pub point: Vec3,
    /// The mesh hit.
    pub mesh: u32,
    /// The hit triangle's geometric normal (its front face).
    pub normal: Vec3,
}

/// Close the gaps of a bounce's buffer: pixels whose ray hits the scene are normalised to full
/// coverage, and those no splat reached (between the discs of a surface a few millimetres
/// away, which leave holes there: a receiver 1 mm from a wall saw 112 of its 256 pixels
/// empty) take the light of the surfel nearest the hit point, on the hit mesh and facing the
/// same way. Pixels the splats cover fully are closed without a ray (in a closed room, most:
/// the rays were half a bounce's time). The pixels that hold more than one surface are then
/// traced finely (`trace_mixed_pixels`): all of a `diffuse` receiver's, and a directional
/// receiver's at its horizon.
pub fn close_buffer(
    senders: &Senders,
    (accel, scene): (&Accel, &Scene),
    (s, diffuse): (&Surfel, bool),
    mb: &mut Microbuffer,
) {
    let covered = |alpha: f32| alpha >= 1.0;
    let hits = pixel_hits(accel, scene, s, mb, |k| !covered(mb.alpha[k]));
    let closed: Vec<bool> = (0..hits.len())
        .map(|k| covered(mb.alpha[k]) || hits[k].is_some())
        .collect();
    mb.close_gaps(|k| closed[k]);
    trace_mixed_pixels(senders, accel, (scene, s, diffuse), mb);
    for (k, hit) in hits.iter().enumerate() {
        let Some(h) = hit else { continue };
        if mb.alpha[k] > 0.0 {
            continue;
        }
        let towards = mb.frame.to_world(-mb.pixels[k].dir);
        if let Some(lookup) = senders.lookup_at(h.point, h.mesh, h.normal, towards, s.mesh) {
            mb.fill_pixel_from(k, senders.evaluated(lookup), lookup);
        }
    }
}

/// Rays per side of a mixed pixel's grid (`trace_mixed_pixels`): 9 rays, each a ninth of
/// the pixel. On ceiling-diffuse (default bake and render against Mitsuba's max_depth 64) 2², 3²
/// and 4² rays gave relMSE 1.33e-3, 1.23e-3 and 1.32e-3, on cbox-diffuse 2.43e-4, 2.41e-4
/// and 2.41e-4: the render's bright pixels resolve what a mixed pixel leaves, and 3² costs
/// two thirds of 4².
pub const MIXED_RAYS_PER_SIDE: u32 = 3;

/// Trace the pixels of surfel `s`'s closed buffer that hold more than one surface
/// ([`Microbuffer::is_mixed`]): [`MIXED_RAYS_PER_SIDE`]² rays through equal parts of each,
/// each a link to the surfel nearest its hit (on the hit mesh, facing its way), replace what
/// the cut splatted there. Within a pixel the splats composite by coverage alone, so a small
/// occluder dims a layer behind it by its share of the pixel, whatever part of that layer it
/// hides: a lamp turned to the ceiling hid the brightest part of its own spot from the floor
/// below, and the cache came out 3–7 % too bright by region where that spot lit the room
/// (docs/bounces.md, "Mixed pixels traced"). The rays see which part is hidden.
///
/// A directional receiver (not `diffuse`) traces only its mixed pixels that border the
/// horizon ([`Microbuffer::at_horizon`]), where the cut's footprints are clipped and a
/// glossy surface reflects grazing light most strongly: a gold box under that lamp's spot
/// sent the floor 1.6–2.0 times the path tracer's light, 1.04–1.23 with these pixels traced
/// (0.99–1.10 with all). Its other mixed pixels keep the cut's light: traced, they moved the
/// conductor furnace of tests/furnace.rs from +0.4 % to −2.9 % at ρ = 0.99 (−0.1 % to
/// −0.8 % at 0.9), a bias not yet understood; the horizon's pixels left it at +0.4 %.
fn trace_mixed_pixels(
    senders: &Senders,
    accel: &Accel,
    (scene, s, diffuse): (&Scene, &Surfel, bool),
    mb: &mut Microbuffer,
) {
    let (p, err) = s.position_with_error(scene);
    let ng = Vec3A::from(s.n);
    let mut traced = Vec::new();
    let mut found = Vec::new();
    let mut near = None;
    for k in 0..mb.pixels.len() {
        if !mb.is_mixed(k) {
            continue;
        }
        if !diffuse && !mb.at_horizon(k) {
            continue;
        }
        traced.push((k, found.len(), MIXED_RAYS_PER_SIDE * MIXED_RAYS_PER_SIDE));
        for (local, cos) in mb.pixel_directions(k, MIXED_RAYS_PER_SIDE) {
            let w = mb.frame.to_world(local).normalize();
            let origin = Vec3::from(offset_origin(p, err, ng, Vec3A::from(w)));
            let Some(h) = accel.closest_hit(origin, w, 0.0, f32::INFINITY) else {
                continue;
            };
            let [a, b, c] = h.corners.map(Vec3::from);
            let normal = (b - a).cross(c - a).normalize_or_zero();
            // The ray beside this one found a surfel near this hit: the search starts there.
            if let Some(i) = senders.surfel_at(origin + w * h.t, h.mesh, normal, near) {
                near = Some(i);
                let lookup = senders.surfel_read(i, -w, s.mesh);
                found.push((lookup, senders.evaluated(lookup), cos));
            }
        }
    }
    mb.set_traced_from(&traced, &found);
}

/// `map`, thresholded from `texels` (a surfel's sphere map, normal `n`), scaled channel by
/// channel to the flux Σ L |n·ω| of the texels (every texel has the same solid angle): the
/// light a surfel sends out through both faces, which thresholding changes a little (it keeps
/// the mean over all directions, not the cosine-weighted one). The same rule as the BSDF
/// operator's ([`BsdfOperator::outgoing`](super::BsdfOperator::outgoing)): thresholding moves
/// light between directions but neither creates nor loses it. Without it, the light sent at
/// [`SENT_TAU_FACTOR`] times the cache's threshold lost 0.5 % a bounce in the conductor
/// furnace of ρ = 0.9, which its stiff tail turned into 3 % (tests/furnace.rs). What a lookup
/// reads is clamped at zero, so the thresholded map's flux is measured so too.
fn with_flux_of(map: SparseHaar<Rgb>, texels: &[Rgb], n: Vec3) -> SparseHaar<Rgb> {
    let mut decoded = Vec::new();
    map.texels_into(&mut decoded);
    // The exact and the thresholded texels' fluxes in one pass, each cosine found once.
    let (exact, kept) = texels
        .iter()
        .zip(&decoded)
        .zip(texel_directions(map.levels()))
        .fold((Rgb::ZERO, Rgb::ZERO), |(e, k), ((l, d), w)| {
            let cos = w.dot(n).abs();
            (e + *l * cos, k + d.max(Rgb::ZERO) * cos)
        });
    let scale = Rgb::select(kept.cmpgt(Rgb::ZERO), exact / kept, Rgb::ONE);
    map.map_coefficients(|c| c * scale)
}

/// What one thread's gathers reuse from group to group: the traversal stack and finished
/// microbuffers, whose splat and link lists keep their capacity (a glass receiver splats
/// thousands of senders; growing fresh lists for each receiver was a tenth of the first
/// bounce, most of it the kernel clearing the new pages).
#[derive(Default)]
struct Scratch {
    stack: Vec<u32>,
    buffers: Vec<Microbuffer>,
    links: LinkScratch,
}

impl Scratch {
    /// The most buffers kept: a group's members at once, and one more of another size.
    const KEPT: usize = GROUP_SURFELS as usize + 1;

    /// Keep `buffers` for the next groups (as many as [`Scratch::KEPT`]).
    fn keep(&mut self, buffers: impl Iterator<Item = Microbuffer>) {
        let room = Self::KEPT.saturating_sub(self.buffers.len());
        self.buffers.extend(buffers.take(room));
    }
}

/// What a receiver gathered: a diffuse one the cosine convolution of its incident radiance
/// (before its reflectance), a directional one its incident radiance per pixel of its
/// microbuffer (before its BSDF's operator). Both are linear in the light sent, so the
/// bounces' sum is gathered once and turned into outgoing radiance once, at the end, instead
/// of adding every bounce's thresholded map to the total (a fifth of a later bounce).
#[derive(Clone, Debug)]
enum Incident {
    Nothing,
    Diffuse(Rgb),
    Directional(Vec<Rgb>),
}

impl Incident {
    /// Add `other` times `weight`, channel by channel (both of one receiver, so of the same
    /// kind).
    fn add(&mut self, other: Incident, weight: Rgb) {
        match (self, other) {
            (Incident::Diffuse(a), Incident::Diffuse(b)) => *a += b * weight,
            (Incident::Directional(a), Incident::Directional(b)) => {
                for (x, y) in a.iter_mut().zip(b) {
                    *x += y * weight;
                }
            }
            (this @ Incident::Nothing, mut other) => {
                other.scale(weight);
                *this = other;
            }
            _ => {}
        }
    }

    fn scale(&mut self, k: Rgb) {
        match self {
            Incident::Nothing => {}
            Incident::Diffuse(a) => *a *= k,
            Incident::Directional(a) => a.iter_mut().for_each(|x| *x *= k),
        }
    }
}

/// A bounce's light: every surfel's (the receivers' outgoing radiance, zero for the others),
/// and what each receiver gathered.
type BounceLight = (Vec<SurfelRadiance>, Vec<(u32, Incident)>);

/// What gathering a receiver's microbuffer traces and looks up.
struct GatherGeometry {
    /// The scene's triangles, for the rays that close a buffer's gaps.
    accel: Accel,
    /// The tree as senders of geometry alone.
    senders: Senders,
}

/// What a bounce's gather needs: the scene, the senders' geometry and the receivers' BSDFs.
struct Gather<'a> {
    scene: &'a Scene,
    /// `None` where every receiver replays kept links and none gathers.
    geometry: Option<&'a GatherGeometry>,
    surfels: &'a [Surfel],
    /// The cache's threshold, and that of the light sent between bounces
    /// ([`SENT_TAU_FACTOR`]).
    tau: f32,
    sent_tau: f32,
    bsdfs: &'a [Bsdf],
    /// The surfels' shading normals: their microbuffers' and operators' frames.
    normals: &'a [Vec3],
    ops: &'a [Option<SurfelOperator>],
    slots: &'a Slots,
}

impl Gather<'_> {
    /// The links of every member of `group` (see [`Gather::buffers`]).
    fn record(&self, group: &Cluster, scratch: &mut Scratch) -> Vec<ReceiverLinks> {
        let buffers = self.buffers(group, scratch);
        let links: Vec<ReceiverLinks> = buffers
            .iter()
            .map(|(i, mb)| {
                let op = &self.ops[*i as usize];
                let links =
                    ReceiverLinks::of_buffer(*i, mb, op.is_none(), self.slots, &mut scratch.links);
                match op {
                    Some(op) => links.with_map_texels(self.map_texels(*i, op)),
                    None => links,
                }
            })
            .collect();
        scratch.keep(buffers.into_iter().map(|(_, mb)| mb));
        links
    }

    /// The closed microbuffer of every member of `group`, recording links: gathered with the
    /// group's far senders shared (docs/method.md §8.3), and closed.
    fn buffers(&self, group: &Cluster, scratch: &mut Scratch) -> Vec<(u32, Microbuffer)> {
        let Some(GatherGeometry { accel, senders }) = self.geometry else {
            unreachable!("the gather's geometry is built wherever a group gathers")
        };
        let Scratch { stack, buffers, .. } = scratch;
        let surfels = self.surfels;
        let side = |i: u32| {
            self.ops[i as usize]
                .as_ref()
                .map_or(Microbuffer::DEFAULT_SIDE, |op| op.shared.n)
        };
        let mut buffer = |i: u32| {
            let spherical = self.bsdfs[i as usize].is_two_sided();
            let frame = Frame::from_normal(self.normals[i as usize]);
            let n = side(i);
            match buffers.iter().rposition(|mb| mb.n == n) {
                Some(k) => {
                    let mut mb = buffers.swap_remove(k);
                    mb.reset(spherical, frame);
                    mb
                }
                None => {
                    let mut mb = Microbuffer::new(n, spherical, frame);
                    mb.record_links();
                    mb
                }
            }
        };
        let closed = |i: u32, mut mb: Microbuffer| {
            let s = &surfels[i as usize];
            let diffuse = self.ops[i as usize].is_none();
            close_buffer(senders, (accel, self.scene), (s, diffuse), &mut mb);
            (i, mb)
        };
        let mut gather = if let [_] = group.members[..] {
            ClusterGather::alone(senders)
        } else {
            let a = &surfels[group.active as usize];
            let spherical = self.bsdfs[group.active as usize].is_two_sided();
            let active = (a.p, a.mesh, Frame::from_normal(a.n));
            let receivers = ClusterReceivers::of(group, active, spherical, true);
            let n = group
                .members
                .iter()
                .map(|&i| side(i))
                .max()
                .unwrap_or(Microbuffer::DEFAULT_SIDE);
            ClusterGather::shared(senders, &receivers, VIEW_EPS, n)
        };
        group
            .members
            .iter()
            .map(|&i| {
                let s = &surfels[i as usize];
                let mut mb = buffer(i);
                gather.fill(s.p, s.mesh, &mut mb, stack);
                closed(i, mb)
            })
            .collect()
    }

    /// Per texel of directional surfel `i`'s sphere map, the texel of its operator's grid
    /// that feeds it (in the frame of its microbuffer).
    fn map_texels(&self, i: u32, op: &SurfelOperator) -> Vec<u16> {
        let levels = map_levels(&self.bsdfs[i as usize]).unwrap_or(3);
        let frame = Frame::from_normal(self.normals[i as usize]);
        op.shared.map_texels(frame, levels)
    }

    /// One bounce: every receiver's outgoing radiance from the light in `values` (per read
    /// slot), through the `kept` links and the links of the `regathered` groups, recorded
    /// again (the other surfels' stays zero, for [`Receivers::blend`]); and what each
    /// receiver gathered, its [`Incident`] light.
    fn evaluate(
        &self,
        kept: &[Vec<ReceiverLinks>],
        regathered: &[Cluster],
        index: &SlotIndex,
        values: &[Rgb],
        cancel: &AtomicBool,
    ) -> Result<BounceLight> {
        let outgoing = |l: &ReceiverLinks| {
            let incident = self.incident(l, values);
            let light = self.outgoing(l.surfel, &incident, l.map_texels(), self.sent_tau);
            (l.surfel, incident, light)
        };
        let mut light = vec![SurfelRadiance::Rgb(Rgb::ZERO); self.surfels.len()];
        let from_kept: Vec<(u32, Incident, SurfelRadiance)> =
            kept.par_iter().flatten().map(outgoing).collect();
        let from_regathered: Vec<Vec<(u32, Incident, SurfelRadiance)>> = regathered
            .par_iter()
            .map_init(Scratch::default, |scratch, group| {
                if cancel.load(Ordering::Relaxed) {
                    return Vec::new();
                }
                let mut links = self.record(group, scratch);
                links
                    .iter_mut()
                    .map(|l| {
                        l.compact(index);
                        outgoing(l)
                    })
                    .collect()
            })
            .collect();
        if cancel.load(Ordering::Relaxed) {
            return Err(Error::Cancelled);
        }
        let gathered = from_kept
            .into_iter()
            .chain(from_regathered.into_iter().flatten());
        let incident = gathered
            .map(|(i, incident, l)| {
                light[i as usize] = l;
                (i, incident)
            })
            .collect();
        Ok((light, incident))
    }

    /// A receiver's incident light from its links and the light in `values`.
    fn incident(&self, links: &ReceiverLinks, values: &[Rgb]) -> Incident {
        match &self.ops[links.surfel as usize] {
            Some(_) => Incident::Directional(links.pixel_radiance(values)),
            None => Incident::Diffuse(links.diffuse_sum(values)),
        }
    }

    /// Receiver `i`'s light from what it gathered: for a diffuse surfel the cosine
    /// convolution before its reflectance (one RGB value, see [`Gather::reflect`]), for the
    /// others D = V·C resampled onto their sphere map (`map_texels`, see
    /// [`Gather::map_texels`]).
    fn outgoing(
        &self,
        i: u32,
        incident: &Incident,
        map_texels: &[u16],
        tau: f32,
    ) -> SurfelRadiance {
        match (&self.ops[i as usize], incident) {
            (Some(op), Incident::Directional(pixels)) => {
                let texels = op.sphere_map(pixels, map_texels);
                // The map has 4^levels texels.
                let side = 1 << (texels.len().trailing_zeros() / 2);
                let map = SparseHaar::compress(&Haar2d::forward(&texels, side), tau);
                SurfelRadiance::Map(with_flux_of(map, &texels, self.surfels[i as usize].n))
            }
            (_, Incident::Diffuse(sum)) => SurfelRadiance::Rgb(*sum),
            _ => SurfelRadiance::Rgb(Rgb::ZERO),
        }
    }

    /// Every receiver's light from what it gathered over all the bounces (see
    /// [`Gather::outgoing`]); zero for the others.
    /// The `kept` links' map texels are reused; those of regathered receivers are found
    /// again.
    fn outgoing_of_all(
        &self,
        gathered: &[Incident],
        kept: &[Vec<ReceiverLinks>],
    ) -> Vec<SurfelRadiance> {
        let mut recorded: Vec<&[u16]> = vec![&[]; gathered.len()];
        for l in kept.iter().flatten() {
            recorded[l.surfel as usize] = l.map_texels();
        }
        gathered
            .par_iter()
            .zip(recorded)
            .enumerate()
            .map(|(i, (incident, recorded))| {
                let i = i as u32;
                let found;
                let texels = match (&self.ops[i as usize], incident) {
                    (Some(op), Incident::Directional(_)) if recorded.is_empty() => {
                        found = self.map_texels(i, op);
                        &found[..]
                    }
                    _ => recorded,
                };
                self.outgoing(i, incident, texels, self.tau)
            })
            .collect()
    }

    /// Every surfel's outgoing radiance from its gathered (or blended) light: diffuse surfels
    /// multiply it by their reflectance, which stays their own where neighbours' light is
    /// blended.
    fn reflect(&self, light: &mut [SurfelRadiance]) {
        light
            .par_iter_mut()
            .zip(self.bsdfs)
            .zip(self.ops)
            .for_each(|((l, bsdf), op)| match (op, bsdf, &*l) {
                (Some(_), _, _) => {}
                (None, Bsdf::Diffuse(d), SurfelRadiance::Rgb(sum)) => {
                    *l = SurfelRadiance::Rgb((d.reflectance * *sum).max(Rgb::ZERO))
                }
                (None, _, _) => *l = SurfelRadiance::Rgb(Rgb::ZERO),
            });
    }
}

#[cfg(test)]
mod tests {
    use super::super::bsdf_operator::Operators;
    use super::*;
    use crate::bake::{bake, BakeSettings};

    /// The bundled cbox-rough (diffuse walls, a rough conductor, a glass sphere) and its bake
    /// of `points` surfels with `light_samples` each, threshold `tau`, direct light only.
    fn rough_box(points: usize, light_samples: u32, tau: f32) -> (Scene, Baked) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/mitsuba/cbox-rough.gltf");
        let scene = Scene::load(&path).expect("bundled scene");
        let settings = BakeSettings {
            points,
            light_samples,
            tau,
            ..BakeSettings::preset(crate::bake::Quality::Draft).direct_only()
        };
        let baked = bake(&scene, &settings, &|_, _| {}).expect("bakes");
        (scene, baked)
    }

    /// The senders the bounces build from the bake in memory look up what those read back
    /// from its cache file do: the same lookup and projected area, node by node, along
    /// directions all round (exact: both rebuild the same maps from the same records).
    #[test]
    fn senders_in_memory_are_the_cache_senders() {
        let (_, baked) = rough_box(2000, 4, 2e-3);
        let from_file = Senders::from_cache(
            &crate::bake::store::in_memory(Path::new("test"), &baked).expect("cache"),
        )
        .expect("senders");
        let in_memory = geometry_senders(&baked).expect("senders");
        assert_eq!(from_file.nodes.len(), in_memory.nodes.len());
        let directions = crate::haar::texel_directions(3);
        let mut compared = 0;
        for j in 0..from_file.nodes.len() as u32 {
            for &w in directions {
                for hidden in [false, true] {
                    let a = from_file.seen_lookup(j, w, 0, hidden);
                    let b = in_memory.seen_lookup(j, w, 0, hidden);
                    assert_eq!(a, b, "node {j} along {w}");
                    compared += 1;
                }
            }
        }
        assert!(compared > 100_000, "{compared}");
    }

    /// The recorded links, replayed against the light the senders were loaded with, give
    /// what the gather itself composites: per pixel for directional receivers, and the cosine
    /// convolution for diffuse ones. Both sides are computed from the same splats, so they
    /// differ only by the order of f32 sums (the links are merged by slot): for n terms the
    /// rounding of either order is at most n·2⁻²⁴ of the sum of their magnitudes, about 1e-4
    /// for the ≈ 2 000 terms of a buffer, hence 1e-4 of the brightest pixel. Measured: at most
    /// 5.7e-7 of it over 335 diffuse and 93 directional receivers. A map's texel read by a
    /// traced pixel adds the rounding of the map's coding (see `rounding` below).
    /// Groups of cbox-rough (diffuse walls, a rough conductor, a glass sphere) exercise the
    /// shared far buffer, the closing rays and the holes filled from the nearest surfel.
    #[test]
    fn links_replay_the_gather() {
        let (scene, baked) = rough_box(3000, 16, 0.0);
        let accel = Accel::build(&scene);
        let bsdfs = &baked.bsdfs;
        let ops = Operators::default().of_each(bsdfs, 1e-2, |b| !matches!(b, Bsdf::Diffuse(_)));
        let cache = crate::bake::store::in_memory(Path::new("test"), &baked).expect("cache");
        let senders = Senders::from_cache(&cache).expect("senders");
        let slots = Slots::new(&baked.tree, &baked.radiance, baked.plan.map_levels).expect("slots");
        let geometry = GatherGeometry { accel, senders };
        let gather = Gather {
            scene: &scene,
            geometry: Some(&geometry),
            surfels: &baked.surfels,
            tau: 0.0,
            sent_tau: 0.0,
            bsdfs,
            normals: &baked.shading_normals,
            ops: &ops,
            slots: &slots,
        };
        let groups = receiver_groups(&baked.tree, &baked.surfels);
        let picked: Vec<&Cluster> = groups.iter().step_by(7).collect();
        assert!(picked.iter().any(|g| g.members.len() > 1));
        let mut index = SlotIndex::new(&slots);
        let mut scratch = Scratch::default();
        let mut recorded: Vec<(Microbuffer, ReceiverLinks)> = Vec::new();
        for group in &picked {
            for (i, mb) in gather.buffers(group, &mut scratch) {
                let diffuse = ops[i as usize].is_none();
                let links = ReceiverLinks::of_buffer(i, &mb, diffuse, &slots, &mut scratch.links);
                links.mark(&index);
                recorded.push((mb, links));
            }
        }
        index.freeze();
        let sent: Vec<SurfelRadiance> = baked
            .radiance
            .iter()
            .zip(&baked.emitted)
            .zip(&baked.surfels)
            .map(|((r, e), s)| without_emission(r, *e, s.n, 0.0))
            .collect();
        let read = read_nodes(&slots, &index, &baked.tree);
        let mut values = Vec::new();
        fill_slots(&baked, (&slots, &index, &read), &sent, &mut values);
        // A lookup of a surfel's map reads the cache's coded map on one side and the bake's
        // own texels on the other: they differ by the rounding of the map's transform, up to
        // 2⁻²⁰ (16 ulps, for its levels of sums and differences) of the brightest light any
        // surfel sends, whatever the receiver's own buffer holds (a receiver that sees only
        // the dark side of glossy maps reads that rounding alone: 5e-10 here).
        let brightest_sent = sent
            .iter()
            .map(|r| match r {
                SurfelRadiance::Rgb(c) => c.max_element(),
                SurfelRadiance::Map(m) => {
                    let mut texels = Vec::new();
                    m.texels_into(&mut texels);
                    texels.iter().map(|t| t.max_element()).fold(0.0, f32::max)
                }
            })
            .fold(0.0, f32::max);
        let rounding = brightest_sent / (1 << 20) as f32;
        let (mut diffuse, mut directional) = (0, 0);
        for (mb, mut links) in recorded {
            links.compact(&index);
            let i = links.surfel as usize;
            let brightest = mb
                .radiance
                .iter()
                .map(|l| l.max_element())
                .fold(0.0, f32::max);
            let tolerance = 1e-4 * brightest + rounding;
            if ops[i].is_some() {
                directional += 1;
                // A directional receiver's links give each pixel's cosine-weighted radiance
                // over its mean cosine (`ReceiverLinks::of_buffer`).
                let gathered: Vec<Rgb> = (0..mb.pixels.len())
                    .map(|k| mb.cos_radiance[k] / mb.mean_cos(k))
                    .collect();
                for (k, (ours, theirs)) in links
                    .pixel_radiance(&values)
                    .iter()
                    .zip(&gathered)
                    .enumerate()
                {
                    assert!(
                        (*ours - *theirs).abs().max_element() <= tolerance,
                        "surfel {i} pixel {k}: links {ours} against the gather's {theirs}"
                    );
                }
            } else {
                diffuse += 1;
                let Bsdf::Diffuse(d) = &bsdfs[i] else {
                    unreachable!()
                };
                let ours = d.reflectance * links.diffuse_sum(&values);
                let theirs = mb.convolve(&bsdfs[i], Vec3::Z);
                assert!(
                    (ours - theirs).abs().max_element() <= tolerance,
                    "surfel {i}: links {ours} against the gather's {theirs}"
                );
            }
        }
        assert!(
            diffuse > 50 && directional > 10,
            "{diffuse} diffuse, {directional} directional"
        );
    }
}
