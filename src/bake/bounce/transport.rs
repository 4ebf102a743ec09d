//! The bounces' light transport, computed once and replayed against every bounce's light
//! (docs/design.md §12: "transport is computed once").
//!
//! A receiver's gather (tree cut, splats, compositing, the rays that close its gaps) depends on
//! geometry alone: every pixel of its closed microbuffer is a weighted sum of [`Lookup`]s, the
//! places where a sender's radiance is read (see [`crate::gather::lookup`]). The first bounce
//! records those sums; every bounce then evaluates them against the light the previous one
//! left, which costs a table fill and a dot product per receiver instead of a gather.
//!
//! - **Slots.** Every quantity a lookup can read has a slot: a diffuse surfel's RGB, each
//!   texel of a surfel's map, and per inner node the three components of S = Σ A L n (its
//!   exact diffuse radiance is S·u) and each texel of its radiant intensity I, at the tree's
//!   resolution. A lookup becomes one or
//!   three (slot, factor) terms. Only slots some receiver reads are kept (a bitmap and its
//!   ranks), and each bounce fills them once: surfels' maps decoded once, S summed bottom-up,
//!   and node intensities summed exactly from their surfels' maps (only for the nodes some
//!   receiver reads, [`read_nodes`]; a fifth of the inner nodes in the Cornell-class
//!   scenes). Not the tree coded at the cache's threshold, which a render of that light
//!   would read: rebuilding nodes below the split level from their ancestors' G and H cost
//!   a third of a later bounce, and the conductor furnaces (tests/furnace.rs) measured
//!   +0.16 %, −0.10 %, +0.46 % with the exact sums against +0.16 %, −0.15 %, +0.40 % with
//!   the coded tree.
//! - **Receivers.** A diffuse receiver's outgoing radiance is ρ ⊙ Σ w·L(slot): the cosine
//!   convolution is folded into the weights and the terms merged by slot. A directional one
//!   keeps its pixels (Σ w·L(slot) each), which its BSDF operator turns into its map.
//! - **Memory.** The terms of whole receiver groups are kept in group order while they fit
//!   the budget; the groups past it gather again in every bounce, through the same code, so
//!   the cache does not depend on the budget (tests/bake.rs).
//! - **Determinism.** Terms are sorted by slot (and pixel) and summed in that order; which
//!   groups are kept depends on their sizes alone, never on threads.

use super::run::Run;
use crate::bsdf::Diffuse;
use crate::gather::lookup::Lookup;
use crate::gather::microbuffer::{group_by_pixel, Microbuffer};
use crate::haar::{texel_at, SparseHaar};
use crate::spectrum::Rgb;
use crate::surfels::radiance::SurfelRadiance;
use crate::surfels::tree::{SurfelTree, NONE};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Where every readable quantity of the tree has its (dense) slot (see the module docs).
pub struct Slots {
    /// Per surfel: its first slot, and its map's levels (`None`: one RGB slot).
    surfel_base: Vec<u32>,
    surfel_levels: Vec<Option<u32>>,
    /// Per node: the first slot of an inner node (S's three, then I's texels).
    node_base: Vec<u32>,
    /// The levels of the tree's intensity maps.
    tree_levels: u32,
    total: u64,
}

/// A bake whose slots do not fit 32-bit indices.
#[derive(Debug)]
pub struct TooManySlots(pub u64);

impl Slots {
    /// The slots of `tree`, whose maps have `levels`, over surfels whose radiance has the
    /// kinds of `radiance`.
    pub fn new(
        tree: &SurfelTree,
        radiance: &[SurfelRadiance],
        levels: u32,
    ) -> Result<Slots, TooManySlots> {
        let surfel_levels: Vec<Option<u32>> = radiance
            .iter()
            .map(|r| match r {
                SurfelRadiance::Rgb(_) => None,
                SurfelRadiance::Map(m) => Some(m.levels()),
            })
            .collect();
        let mut total = 0u64;
        let mut surfel_base = Vec::with_capacity(radiance.len());
        for l in &surfel_levels {
            surfel_base.push(total as u32);
            total += l.map_or(1, |l| 1u64 << (2 * l));
        }
        let mut node_base = vec![u32::MAX; tree.nodes.len()];
        for (j, node) in tree.nodes.iter().enumerate() {
            if !node.is_leaf() {
                node_base[j] = total.min(u64::from(u32::MAX)) as u32;
                total += 3 + (1u64 << (2 * levels));
            }
        }
        if total >= u64::from(u32::MAX) {
            return Err(TooManySlots(total));
        }
        Ok(Slots {
            surfel_base,
            surfel_levels,
            node_base,
            tree_levels: levels,
            total,
        })
    }

    /// The fewest slots a tree of `points` surfels with maps of `levels` has: one per surfel,
    /// and S's three and I's texels per inner node (a binary tree of one surfel per leaf has
    /// `points − 1`).
    pub(crate) fn fewest(points: u64, levels: u32) -> u64 {
        points + points.saturating_sub(1) * (3 + (1u64 << (2 * levels)))
    }

    /// How many slots there are.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// The terms (slot, factor) whose sum is the radiance at `lookup`.
    fn terms(&self, lookup: Lookup, mut push: impl FnMut(u32, f32)) {
        match lookup {
            Lookup::Nothing => {}
            Lookup::SurfelRgb { surfel } => push(self.surfel_base[surfel as usize], 1.0),
            Lookup::SurfelMap { surfel, point, .. } => {
                let levels = self.surfel_levels[surfel as usize].unwrap_or(0);
                push(
                    self.surfel_base[surfel as usize] + texel_index(point, levels),
                    1.0,
                );
            }
            Lookup::NodeNormal { node, u } => {
                let base = self.node_base[node as usize];
                for (axis, f) in u.to_array().into_iter().enumerate() {
                    if f != 0.0 {
                        push(base + axis as u32, f);
                    }
                }
            }
            Lookup::NodeMap { node, point, scale } => {
                let levels = self.tree_levels;
                push(
                    self.node_base[node as usize] + 3 + texel_index(point, levels),
                    scale,
                );
            }
        }
    }
}

/// The row-major index of the texel of a map of `levels` that holds `point` (the order of
/// [`Haar2d::inverse`](crate::haar::Haar2d::inverse)).
fn texel_index(point: glam::Vec2, levels: u32) -> u32 {
    let (x, y) = texel_at(point, 1 << levels);
    (y << levels) + x
}

/// The slots some receiver reads, and each one's index among them.
pub struct SlotIndex {
    words: Vec<AtomicU64>,
    /// After [`SlotIndex::freeze`]: the read slots before each word.
    ranks: Vec<u32>,
}

impl SlotIndex {
    /// An index over `slots` with none marked read yet.
    pub fn new(slots: &Slots) -> SlotIndex {
        SlotIndex {
            words: (0..slots.total.div_ceil(64))
                .map(|_| AtomicU64::new(0))
                .collect(),
            ranks: Vec::new(),
        }
    }

    /// A frozen index whose bitmap is `words` (as [`SlotIndex::words`] gave them).
    pub(super) fn from_words(words: Vec<u64>) -> SlotIndex {
        let mut index = SlotIndex {
            words: words.into_iter().map(AtomicU64::new).collect(),
            ranks: Vec::new(),
        };
        index.freeze();
        index
    }

    /// The bitmap of read slots, 64 a word.
    pub(super) fn words(&self) -> Vec<u64> {
        self.words
            .iter()
            .map(|w| w.load(Ordering::Relaxed))
            .collect()
    }

    fn mark(&self, slot: u32) {
        self.words[(slot / 64) as usize].fetch_or(1 << (slot % 64), Ordering::Relaxed);
    }

    /// Number the marked slots in slot order.
    pub(crate) fn freeze(&mut self) {
        let mut count = 0u32;
        self.ranks = self
            .words
            .iter()
            .map(|w| {
                let before = count;
                count += w.load(Ordering::Relaxed).count_ones();
                before
            })
            .collect();
    }

    /// How many slots are read.
    pub(crate) fn len(&self) -> usize {
        match (self.ranks.last(), self.words.last()) {
            (Some(&r), Some(w)) => (r + w.load(Ordering::Relaxed).count_ones()) as usize,
            _ => 0,
        }
    }

    /// The index of marked slot `slot` among the read ones.
    fn compact(&self, slot: u32) -> u32 {
        self.rank(slot) as u32
    }

    /// How many read slots lie before `slot` (any slot up to the total).
    fn rank(&self, slot: u32) -> usize {
        let (word, bit) = ((slot / 64) as usize, slot % 64);
        match self.words.get(word) {
            Some(w) => {
                let below = w.load(Ordering::Relaxed) & ((1u64 << bit) - 1);
                (self.ranks[word] + below.count_ones()) as usize
            }
            None => self.len(),
        }
    }

    /// The read slots in `[begin, begin + count)`, as offsets from `begin`, in order: a word
    /// of the bitmap at a time, so that a bounce touches the set bits, not every slot.
    fn read_in(&self, begin: u32, count: u32) -> impl Iterator<Item = u32> + '_ {
        let end = begin + count;
        let words = (begin / 64) as usize..end.div_ceil(64) as usize;
        words.flat_map(move |w| {
            let base = w as u32 * 64;
            // Keep the bits of this word that lie in [begin, end) (base < end, and
            // begin − base < 64 in the first word).
            let low = begin.saturating_sub(base);
            let high = (end - base).min(64);
            let range = (u64::MAX << low)
                & if high == 64 {
                    u64::MAX
                } else {
                    (1 << high) - 1
                };
            let mut bits = self.words[w].load(Ordering::Relaxed) & range;
            std::iter::from_fn(move || {
                (bits != 0).then(|| {
                    let b = bits.trailing_zeros();
                    bits &= bits - 1;
                    base + b - begin
                })
            })
        })
    }
}

/// One (slot, weight) term of a receiver's light.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct Term {
    pub(super) slot: u32,
    pub(super) w: f32,
}

/// The lists a thread's [`ReceiverLinks::of_buffer`] works in, kept from receiver to receiver
/// with their capacity: only the terms kept are allocated anew, at their exact size.
#[derive(Debug, Default)]
pub struct LinkScratch {
    order: Vec<u32>,
    ends: Vec<u32>,
    run: Vec<Term>,
    terms: Vec<Term>,
}

/// Append `terms` to `out` sorted by slot, the weights of equal slots summed. Ties are
/// broken by the weight's bits, so the sums' order, and with it every rounding, depends on the
/// set of terms alone, never on the order they were produced in.
fn merge_by_slot(terms: &mut [Term], out: &mut Vec<Term>) {
    terms.sort_unstable_by_key(|t| (t.slot, t.w.to_bits()));
    let begin = out.len();
    for &t in terms.iter() {
        match out[begin..].last_mut() {
            Some(last) if last.slot == t.slot => last.w += t.w,
            _ => out.push(t),
        }
    }
}

/// A receiver's recorded gather.
pub struct ReceiverLinks {
    /// The receiving surfel.
    pub surfel: u32,
    /// For a directional receiver, the end of each pixel's terms; empty for a diffuse one.
    pixel_ends: Run<u32>,
    terms: Run<Term>,
    /// For a directional receiver: per texel of its outgoing map, the texel of its operator's
    /// grid it takes its radiance from, or [`NO_TEXEL`](super::bsdf_operator::NO_TEXEL)
    /// (geometry alone, so recorded once).
    map_texels: Run<u16>,
}

impl ReceiverLinks {
    /// The links of surfel `surfel`'s closed buffer `mb` (which recorded links): merged by
    /// slot with the cosine convolution folded in (`diffuse`), or per pixel.
    pub fn of_buffer(
        surfel: u32,
        mb: &Microbuffer,
        diffuse: bool,
        slots: &Slots,
        scratch: &mut LinkScratch,
    ) -> ReceiverLinks {
        let LinkScratch {
            order,
            ends,
            run,
            terms,
        } = scratch;
        terms.clear();
        let Some(links) = mb.links() else {
            return ReceiverLinks {
                surfel,
                pixel_ends: Run::default(),
                terms: Run::default(),
                map_texels: Run::default(),
            };
        };
        if diffuse {
            // The diffuse convolution's weight of each pixel (ρ = 1): f(Z, ωₖ) sₖ / |cos θₖ|,
            // folded into its source first (a node splat covers many pixels), then each
            // source expanded to its slots once.
            let unit = Diffuse {
                reflectance: Rgb::ONE,
            };
            let pixel_weight: Vec<f32> = mb
                .pixels
                .iter()
                .map(|px| unit.eval(Vec3::Z, px.dir).x * (px.solid_angle / px.dir.z.abs()))
                .collect();
            let mut per_source = vec![0.0f32; links.sources.len()];
            for e in &links.entries {
                per_source[e.source as usize] += e.w_cos * pixel_weight[e.pixel as usize];
            }
            run.clear();
            for (&lookup, &w) in links.sources.iter().zip(&per_source) {
                if w != 0.0 {
                    slots.terms(lookup, |slot, f| run.push(Term { slot, w: w * f }));
                }
            }
            merge_by_slot(run, terms);
            return ReceiverLinks {
                surfel,
                pixel_ends: Run::default(),
                terms: Box::<[Term]>::from(terms.as_slice()).into(),
                map_texels: Run::default(),
            };
        }
        // Directional: the entries grouped into pixel runs, each run merged by slot. A pixel's
        // light is its cosine-weighted radiance over the pixel's mean |cos θ|: the BSDF
        // operator weights a texel's light by that mean (`bsdf_operator::kernel`), so this is
        // the radiance that carries the flux that arrived. The plain radiance would weigh a
        // sender near the texel's horizon edge by the texel's mean cosine instead of its own:
        // one at cos θ = 0.01 in the outermost ring at 16² (mean cosine 0.12) would send on
        // twelve times the flux it brings (docs/bounces.md, "Light near a glossy receiver's
        // horizon").
        let pixels = mb.pixels.len();
        let entries = &links.entries;
        group_by_pixel(entries.len(), pixels, |i| entries[i].pixel, order, ends);
        let mut pixel_ends = vec![0u32; pixels];
        let mut begin = 0;
        for (k, &end) in ends[..pixels].iter().enumerate() {
            run.clear();
            for &i in &order[begin..end as usize] {
                let e = &entries[i as usize];
                let w = e.w_cos / mb.mean_cos(k);
                if w != 0.0 && w.is_finite() {
                    let lookup = links.sources[e.source as usize];
                    slots.terms(lookup, |slot, f| run.push(Term { slot, w: w * f }));
                }
            }
            merge_by_slot(run, terms);
            pixel_ends[k] = terms.len() as u32;
            begin = end as usize;
        }
        ReceiverLinks {
            surfel,
            pixel_ends: pixel_ends.into(),
            terms: Box::<[Term]>::from(terms.as_slice()).into(),
            map_texels: Run::default(),
        }
    }

    /// The same links with the directional receiver's map texels (see
    /// [`ReceiverLinks::map_texels`]).
    pub(crate) fn with_map_texels(mut self, texels: Vec<u16>) -> ReceiverLinks {
        self.map_texels = texels.into();
        self
    }

    /// Links from their parts (as [`ReceiverLinks::parts`] gives them), for a kept
    /// transport read back ([`super::kept`]), which checks them before they are used.
    pub(super) fn from_parts(
        surfel: u32,
        pixel_ends: Run<u32>,
        terms: Run<Term>,
        map_texels: Run<u16>,
    ) -> ReceiverLinks {
        ReceiverLinks {
            surfel,
            pixel_ends,
            terms,
            map_texels,
        }
    }

    /// Whether every array of these links is read in place ([`Run::InPlace`]).
    #[cfg(test)]
    pub(super) fn in_place(&self) -> bool {
        matches!(self.pixel_ends, Run::InPlace { .. })
            && matches!(self.terms, Run::InPlace { .. })
            && matches!(self.map_texels, Run::InPlace { .. })
    }

    /// The pixels' ends, the terms and the map texels.
    pub(super) fn parts(&self) -> (&[u32], &[Term], &[u16]) {
        (&self.pixel_ends, &self.terms, &self.map_texels)
    }

    /// Whether these links can be replayed for a receiver that is directional with a grid
    /// of `pixels` texels and a sphere map of `map_texels` (`None`: a diffuse one) against
    /// `read` read slots: every index in range, the pixels' ends in order. The reason, when
    /// not.
    pub(super) fn check(
        &self,
        directional: Option<(usize, usize)>,
        read: usize,
    ) -> Result<(), String> {
        let (pixels, texels) = directional.unwrap_or((0, 0));
        if self.pixel_ends.len() != pixels || self.map_texels.len() != texels {
            return Err(format!(
                "surfel {}'s links are not of its kind of receiver",
                self.surfel
            ));
        }
        let ends_in_order = self.pixel_ends.windows(2).all(|w| w[0] <= w[1])
            && self
                .pixel_ends
                .last()
                .is_none_or(|&end| end as usize == self.terms.len());
        if !ends_in_order || self.terms.iter().any(|t| t.slot as usize >= read) {
            return Err(format!("surfel {}'s links are out of range", self.surfel));
        }
        Ok(())
    }

    /// Per texel of a directional receiver's outgoing map, its operator texel or
    /// [`NO_TEXEL`](super::bsdf_operator::NO_TEXEL).
    pub fn map_texels(&self) -> &[u16] {
        &self.map_texels
    }

    /// Mark the slots these links read.
    pub fn mark(&self, index: &SlotIndex) {
        for t in self.terms.iter() {
            index.mark(t.slot);
        }
    }

    /// Renumber the slots among the read ones (after [`SlotIndex::freeze`]).
    pub(crate) fn compact(&mut self, index: &SlotIndex) {
        for t in self.terms.to_mut() {
            t.slot = index.compact(t.slot);
        }
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + std::mem::size_of_val(&*self.pixel_ends)
            + std::mem::size_of_val(&*self.terms)
            + std::mem::size_of_val(&*self.map_texels)
    }

    /// Σ w·L over the terms of a diffuse receiver (light from `values`, indexed by compact
    /// slot): its outgoing radiance over ρ.
    pub(crate) fn diffuse_sum(&self, values: &[Rgb]) -> Rgb {
        self.terms
            .iter()
            .fold(Rgb::ZERO, |a, t| a + values[t.slot as usize] * t.w)
    }

    /// Each pixel's radiance, for a directional receiver.
    pub(crate) fn pixel_radiance(&self, values: &[Rgb]) -> Vec<Rgb> {
        // Borrowed once, not per pixel (a run in place checks its bytes on each borrow).
        let terms: &[Term] = &self.terms;
        let mut begin = 0;
        self.pixel_ends
            .iter()
            .map(|&end| {
                let l = terms[begin..end as usize]
                    .iter()
                    .fold(Rgb::ZERO, |a, t| a + values[t.slot as usize] * t.w);
                begin = end as usize;
                l.max(Rgb::ZERO)
            })
            .collect()
    }
}

/// Per node of `tree`, whether a receiver reads some texel of its intensity: the inner
/// nodes whose exact intensity a bounce sums ([`crate::surfels::coding::node_sums`]; a fifth of
/// the inner nodes in the Cornell-class scenes).
pub fn read_nodes(slots: &Slots, index: &SlotIndex, tree: &SurfelTree) -> Vec<bool> {
    let side = 1u32 << slots.tree_levels;
    (0..tree.nodes.len())
        .into_par_iter()
        .map(|j| {
            !tree.nodes[j].is_leaf()
                && index
                    .read_in(slots.node_base[j] + 3, side * side)
                    .next()
                    .is_some()
        })
        .collect()
}

/// What every read slot holds in the light `sent` (per surfel, reflected light only), in
/// compact slot order, into `values` (whose memory is reused from bounce to bounce). Node
/// intensities are read from `sums`, the exact intensity G of every node of `tree` whose
/// texels are read ([`read_nodes`]).
pub(crate) fn slot_values(
    slots: &Slots,
    index: &SlotIndex,
    (tree, sums): (&SurfelTree, &[Option<SparseHaar<Rgb>>]),
    surfels: &[crate::surfels::Surfel],
    sent: &[SurfelRadiance],
    values: &mut Vec<Rgb>,
) {
    values.clear();
    values.resize(index.len(), Rgb::ZERO);
    // Surfel slots come first, surfel by surfel, each surfel's read ones a run of `values`:
    // RGB, or the map's texels (a thresholded map rings a little below zero; what a lookup
    // reads is clamped, as in the render).
    let count = |i: usize| slots.surfel_levels[i].map_or(1, |l| 1u32 << (2 * l));
    let mut runs: Vec<&mut [Rgb]> = Vec::with_capacity(sent.len());
    let mut rest = &mut values[..];
    for i in 0..sent.len() {
        let base = slots.surfel_base[i];
        let read = index.rank(base + count(i)) - index.rank(base);
        let (run, after) = rest.split_at_mut(read);
        runs.push(run);
        rest = after;
    }
    runs.into_par_iter()
        .zip(sent)
        .enumerate()
        .for_each_init(Vec::new, |texels, (i, (run, r))| {
            // A map nobody reads is not decoded.
            if run.is_empty() {
                return;
            }
            match r {
                SurfelRadiance::Rgb(c) => run[0] = c.max(Rgb::ZERO),
                SurfelRadiance::Map(m) => {
                    m.texels_into(texels);
                    let read = index.read_in(slots.surfel_base[i], count(i));
                    for (v, t) in run.iter_mut().zip(read) {
                        *v = texels[t as usize].max(Rgb::ZERO);
                    }
                }
            }
        });
    // Then inner nodes, in node order: S = Σ A L n over the diffuse surfels below (exact, as
    // the render sums it), and the read texels of the intensity G.
    let s_sums = normal_sums(tree, surfels, sent);
    let side = 1u32 << slots.tree_levels;
    let per_node: Vec<(u32, Vec<Rgb>)> = (0..tree.nodes.len())
        .into_par_iter()
        .filter(|&j| !tree.nodes[j].is_leaf())
        .map_init(Vec::new, |decoded, j| {
            let offsets: Vec<u32> = index.read_in(slots.node_base[j], 3 + side * side).collect();
            let s_read = offsets.iter().take_while(|&&k| k < 3).count();
            let mut read: Vec<Rgb> = offsets[..s_read]
                .iter()
                .map(|&k| s_sums[j][k as usize])
                .collect();
            let texels: Vec<u32> = offsets[s_read..].iter().map(|&k| k - 3).collect();
            // `sums` holds G whenever one of its texels is read.
            if let Some(g) = sums[j].as_ref().filter(|_| !texels.is_empty()) {
                let levels = g.trimmed_texels_into(decoded);
                read.extend(read_texels(&texels, slots.tree_levels, (decoded, levels)));
            }
            (!read.is_empty()).then_some((j as u32, read))
        })
        .flatten()
        .collect();
    for (j, read) in per_node {
        let at = index.rank(slots.node_base[j as usize]);
        values[at..at + read.len()].copy_from_slice(&read);
    }
}

/// The texels `read` (row-major) of a map of `levels` a side, from the `texels` of a map of
/// `texel_levels` (which may be coarser: its finer details are zero), clamped at zero (a
/// thresholded map rings a little below it; a lookup's read is clamped, as in the render).
fn read_texels(read: &[u32], levels: u32, (texels, texel_levels): (&[Rgb], u32)) -> Vec<Rgb> {
    let shift = levels - texel_levels.min(levels);
    let side = 1u32 << levels;
    read.iter()
        .map(|&t| {
            let (x, y) = ((t % side) >> shift, (t / side) >> shift);
            texels
                .get(((y << texel_levels) + x) as usize)
                .map_or(Rgb::ZERO, |l| l.max(Rgb::ZERO))
        })
        .collect()
}

/// Per node, S = Σ A L n over the diffuse surfels below, per axis (RGB).
fn normal_sums(
    tree: &SurfelTree,
    surfels: &[crate::surfels::Surfel],
    sent: &[SurfelRadiance],
) -> Vec<[Rgb; 3]> {
    let mut sums = vec![[Rgb::ZERO; 3]; tree.nodes.len()];
    // Children come after their parents.
    for j in (0..tree.nodes.len()).rev() {
        let node = &tree.nodes[j];
        sums[j] = if node.is_leaf() {
            let i = tree.order[node.first as usize] as usize;
            match &sent[i] {
                SurfelRadiance::Rgb(l) => {
                    let an = surfels[i].n * surfels[i].area;
                    [*l * an.x, *l * an.y, *l * an.z]
                }
                SurfelRadiance::Map(_) => [Rgb::ZERO; 3],
            }
        } else {
            node.children
                .iter()
                .filter(|&&c| c != NONE)
                .fold([Rgb::ZERO; 3], |a, &c| {
                    let b = sums[c as usize];
                    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
                })
        };
    }
    sums
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `read_in` lists exactly the marked slots of a range, in order, whatever the range's
    /// alignment to the bitmap's words: against a scan slot by slot.
    #[test]
    fn read_in_lists_the_marked_slots_of_a_range() {
        let total = 1000u32;
        let index = SlotIndex {
            words: (0..total.div_ceil(64)).map(|_| AtomicU64::new(0)).collect(),
            ranks: Vec::new(),
        };
        // A deterministic scatter of marks, with runs across word boundaries.
        let marked = |s: u32| s % 7 == 3 || (s / 61) % 5 == 2 || s == 0 || s == total - 1;
        (0..total)
            .filter(|&s| marked(s))
            .for_each(|s| index.mark(s));
        for (begin, count) in [
            (0, total),
            (0, 1),
            (63, 2),
            (64, 64),
            (5, 200),
            (700, 300),
            (999, 1),
        ] {
            let listed: Vec<u32> = index.read_in(begin, count).collect();
            let expected: Vec<u32> = (begin..begin + count)
                .filter(|&s| marked(s))
                .map(|s| s - begin)
                .collect();
            assert_eq!(listed, expected, "range [{begin}, {})", begin + count);
        }
    }
}
