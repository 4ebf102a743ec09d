//! How many camera samples each pixel takes (adaptive anti-aliasing), decided from one ray
//! through every pixel's centre before the primary pass.
//!
//! - A pixel on an **edge** of what the centre rays see (a 4-neighbour sees another mesh, a
//!   normal turned by more than 25° or a depth step of 5 %) takes samples of a scrambled
//!   (0, 2)-sequence: [`EDGE_SIDE`]² of them on an **outline**, where the light the centre
//!   rays see emitted changes across the edge (an emitter's outline needs them); elsewhere a
//!   round of [`EDGE_ROUND`], and all [`EDGE_SIDE`]² only where the round's samples disagree
//!   ([`needs_more`]): an edge between two walls of one brightness has nothing for the rest
//!   to resolve.
//! - A pixel on a **mirror or clear glass** (roughness below the specular cut-off) also
//!   follows its centre ray's specular chain, every branch of it, to the rough hits at its
//!   ends. Where its neighbours' chains take the same branches to the same surfaces (one
//!   mesh, normals within 25°, ends within 5 % of their distance from the camera) the
//!   reflected or refracted image is a smooth piece of one surface, and the pixel takes
//!   [`SMOOTH_SIDE`]² samples, one per quarter, of which the first gathers for the whole
//!   pixel. Where they differ (the outline of what the mirror shows,
//!   a reflected emitter, a branch that appears or leaves) it is an edge.
//! - Every other pixel takes its centre sample.
//!
//! Before, every edge and every mirror and glass pixel took 64 samples, since the centre ray
//! alone cannot tell the reflected edges: on cbox-mirror at 512² that was 3.3 M camera
//! samples for 262 144 pixels, and the primary pass was 5.5 s of 18.1; now 1.0 M and 2.0 s,
//! at relMSE within 0.1 % (docs/render.md).

use super::primary::{
    trace_primary, CameraSample, LightShare, PrimarySample, PrimarySettings, Receiver,
};
use crate::sampler::{sobol02, Sampler};
use crate::scene::Camera;
use crate::spectrum::{luminance, Rgb};
use crate::trace::{intersect, Tracer};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::ops::Range;

/// Edge pixels take up to EDGE_SIDE² samples of a (0, 2)-sequence for primary hits and
/// direct light (an emitter's edge needs them); one in each quarter of the pixel gathers.
pub(crate) const EDGE_SIDE: u32 = 8;

/// An edge pixel's samples come in rounds of this many, the (0, 2)-sequence's points in
/// order (each round a (0, 4, 2)-net: one point in every 1/16 of the pixel's rows, columns
/// and quarters); after the first, it takes the other three rounds only where the first
/// round's samples disagree ([`needs_more`]).
pub(crate) const EDGE_ROUND: u32 = 16;

/// The first round of an edge pixel goes on to [`EDGE_SIDE`]² samples when the spread of its
/// samples' luminance, squared, exceeds this fraction of their mean's square: relative, so
/// that a scene lit twice as brightly is sampled alike (tests/stability.rs scales the
/// emission by 2^±20 and asks for the same image scaled, bit for bit; a floor like the
/// relative MSE's 0.01 broke that). The same test on the centre rays' emitted light makes an
/// edge an outline. See docs/render.md for the figures.
pub(crate) const EDGE_SPREAD: f32 = 0.5;

/// Mirror and clear-glass pixels whose chains see no edge take SMOOTH_SIDE² samples: the
/// first four points of the (0, 2)-sequence, one in each quarter, for their direct light and
/// what they show; the first gathers for the whole pixel, as a plain pixel's does (but with
/// [`PrimarySettings::smooth_quarters`], for the paths gather, each per quarter). (Gathering
/// per quarter, as an edge does, made each quarter a layer of the sparse grid with anchors of
/// its own: at 512² 6–16 % slower on the glass and mirror scenes, relMSE within 0.2 %.)
pub(crate) const SMOOTH_SIDE: u32 = 2;

/// The edge test's thresholds: neighbours' normals within this cosine (25°) and depths within
/// this fraction of the nearer are one surface.
const SAME_NORMAL: f32 = 0.9;
const SAME_DEPTH: f32 = 0.05;

/// Where one branch of a centre ray's specular chain ends on a rough surface.
#[derive(Clone, Copy, Debug)]
struct ChainEnd {
    /// The chain's signature ([`Receiver::chain`]).
    chain: u64,
    mesh: u32,
    normal: Vec3,
    /// Distance from the camera's ray origin, a lower bound of the chain's length.
    depth: f32,
}

/// The hit through a pixel's centre.
#[derive(Clone, Debug)]
struct CentreHit {
    mesh: u32,
    point: Vec3,
    normal: Vec3,
    depth: f32,
    /// For a mirror or clear glass: the ends of its specular chain, by chain signature.
    /// `None` for a rough surface.
    ends: Option<Vec<ChainEnd>>,
}

/// The centre hits of a rectangle of the image (the pixels a render traces and their
/// neighbours), from which each pixel's sample count follows.
pub(crate) struct PixelSampling {
    width: u32,
    height: u32,
    /// The rectangle `[x0, y0, x1, y1]` (x0 ≤ x < x1, y0 ≤ y < y1) whose centre hits are
    /// kept, row by row.
    rect: [u32; 4],
    centre: Vec<Option<CentreHit>>,
    /// Per pixel, the luminance of the light its centre ray sees emitted: an emitter's, the
    /// environment's where it leaves the scene, along a mirror's or glass's chain too.
    emitted: Vec<f32>,
}

/// How a pixel is sampled ([`PixelSampling::kind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PixelKind {
    /// Its centre.
    Plain,
    /// A mirror or clear glass with no edge in what it shows: [`SMOOTH_SIDE`]² samples.
    Smooth,
    /// An edge between surfaces that emit alike: a round of [`EDGE_ROUND`] samples, and the
    /// rest of [`EDGE_SIDE`]² where they disagree.
    Edge,
    /// An edge where what is seen emitted changes (an emitter's outline, the sky beside an
    /// object): all [`EDGE_SIDE`]² samples at once, since a sliver of the bright side can slip
    /// between a round's samples.
    Outline,
}

impl PixelSampling {
    /// What it keeps per pixel of its rectangle (besides the chain ends of mirrors and glass).
    pub const BYTES_PER_PIXEL: usize = size_of::<Option<CentreHit>>() + size_of::<f32>();

    /// Trace the centre of every pixel of the rectangle `rect` (`[x0, y0, x1, y1]`) of
    /// `camera`'s image, and the chains of those on a mirror or clear glass. [`Self::kind`]
    /// then serves the pixels whose neighbours lie in `rect` or outside the image.
    pub fn new(ctx: &Tracer, camera: &Camera, settings: &PrimarySettings, rect: [u32; 4]) -> Self {
        let (w, h) = (camera.width, camera.height);
        let [x0, y0, x1, y1] = rect;
        let rect_width = x1 - x0;
        let (centre, emitted) = (0..rect_width * (y1 - y0))
            .into_par_iter()
            .map(|at| {
                let pixel = (y0 + at / rect_width) * w + x0 + at % rect_width;
                let film = Vec2::new((pixel % w) as f32 + 0.5, (pixel / w) as f32 + 0.5);
                let (o, d) = camera.generate_ray(film);
                let Some(hit) = intersect(ctx, o, d) else {
                    let sky = ctx.scene.environment.as_ref().map(|e| e.radiance(d));
                    return (None, sky.map_or(0.0, luminance));
                };
                let m = &ctx.scene.materials[ctx.scene.meshes[hit.mesh as usize].material];
                let bsdf = m.bsdf_at(&ctx.scene.textures, hit.uv);
                let smooth = bsdf.alpha().is_some_and(|a| a < settings.specular_below);
                let (ends, emitted) = if smooth {
                    let (ends, emitted) = chain_ends(ctx, settings, o, d, pixel);
                    (Some(ends), emitted)
                } else {
                    let front = hit.frame.n.dot(d) < 0.0;
                    (None, m.emission_at(&ctx.scene.textures, hit.uv, front))
                };
                let centre = CentreHit {
                    mesh: hit.mesh,
                    point: hit.p,
                    normal: hit.frame.n,
                    depth: hit.t,
                    ends,
                };
                (Some(centre), luminance(emitted))
            })
            .unzip();
        PixelSampling {
            width: w,
            height: h,
            rect,
            centre,
            emitted,
        }
    }

    /// Where pixel `(x, y)`, which must lie in the rectangle, is kept.
    fn index(&self, x: u32, y: u32) -> usize {
        let [x0, y0, x1, y1] = self.rect;
        debug_assert!((x0..x1).contains(&x) && (y0..y1).contains(&y));
        ((y - y0) * (x1 - x0) + (x - x0)) as usize
    }

    /// The surfaces that the centre rays of the pixels within `reach` of pixel `(x, y)` (in
    /// the image and the rectangle) hit: mesh, point and shading normal.
    pub fn surfaces_around(
        &self,
        (x, y): (u32, u32),
        reach: u32,
    ) -> impl Iterator<Item = (u32, Vec3, Vec3)> + '_ {
        let [x0, y0, x1, y1] = self.rect;
        let xs = x.saturating_sub(reach).max(x0)..(x + reach + 1).min(x1);
        let ys = y.saturating_sub(reach).max(y0)..(y + reach + 1).min(y1);
        ys.flat_map(move |y| xs.clone().map(move |x| (x, y)))
            .filter_map(|(x, y)| self.centre[self.index(x, y)].as_ref())
            .map(|c| (c.mesh, c.point, c.normal))
    }

    /// How pixel `(x, y)` is sampled (see the module docs).
    pub fn kind(&self, x: u32, y: u32) -> PixelKind {
        let at = self.index(x, y);
        let here = &self.centre[at];
        let neighbours = [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)];
        let neighbours = neighbours.iter().filter_map(|(dx, dy)| {
            let (nx, ny) = (x as i64 + dx, y as i64 + dy);
            let inside = nx >= 0 && ny >= 0 && nx < self.width as i64 && ny < self.height as i64;
            inside.then(|| self.index(nx as u32, ny as u32))
        });
        let mut edge = false;
        let mut outline = false;
        for there in neighbours {
            let apart = match (here, &self.centre[there]) {
                (None, None) => false,
                (Some(a), Some(b)) => {
                    !same_surface(a.mesh, a.normal, a.depth, b.mesh, b.normal, b.depth)
                        || !same_ends(a.ends.as_deref(), b.ends.as_deref())
                }
                _ => true,
            };
            edge |= apart;
            outline |= apart && Spread::of(&[self.emitted[at], self.emitted[there]]).wide();
        }
        match here {
            _ if outline => PixelKind::Outline,
            _ if edge => PixelKind::Edge,
            Some(CentreHit { ends: Some(_), .. }) => PixelKind::Smooth,
            _ => PixelKind::Plain,
        }
    }

    /// Trace the camera samples of pixel `(x, y)`, pushing its receivers: its emission and
    /// direct light (the mean of its samples) and the first hit's AOVs, and how many camera
    /// samples it took. A pixel of one sample takes its centre; a pixel of several the
    /// points of a (0, 2)-sequence scrambled per pixel, of which on an edge the first in each
    /// quarter gathers for the quarter (its receivers weigh a quarter each whatever the
    /// count), elsewhere the first for the whole pixel. An edge pixel takes [`EDGE_ROUND`] samples, and the rest of [`EDGE_SIDE`]² where those
    /// disagree ([`needs_more`]).
    ///
    /// Edge pixels take the points of a scrambled (0, 2)-sequence: every row and column strip
    /// of height 1/64 holds one, so an edge along the pixel grid (an emitter's) is resolved to
    /// 1/64 of the pixel; a jittered 8 × 8 grid leaves each row's eight samples to chance (the
    /// light's edges then held 65 % of the diffuse box's relMSE).
    pub fn trace_pixel(
        &self,
        ctx: &Tracer,
        camera: &Camera,
        settings: &PrimarySettings,
        (x, y): (u32, u32),
        receivers: &mut Vec<Receiver>,
    ) -> (PrimarySample, u32) {
        let kind = self.kind(x, y);
        let (side, count) = match kind {
            PixelKind::Plain => (1, 1),
            PixelKind::Smooth => (SMOOTH_SIDE, SMOOTH_SIDE * SMOOTH_SIDE),
            PixelKind::Edge => (EDGE_SIDE, EDGE_ROUND),
            PixelKind::Outline => (EDGE_SIDE, EDGE_SIDE * EDGE_SIDE),
        };
        let pixel = (x, y);
        let round = self.trace_samples(
            ctx,
            camera,
            settings,
            pixel,
            (side, 0..count),
            Some(receivers),
        );
        if kind != PixelKind::Edge || !needs_more(&round.spread, round.hits, count) {
            return (round.pixel(), count);
        }
        // The rest of the sequence, with direct light of its own (a second set of the pixel's
        // light points, shared out over these samples alone); the first round's samples stay,
        // and its receivers already gather for the quarters.
        let most = EDGE_SIDE * EDGE_SIDE;
        let rest = self.trace_samples(ctx, camera, settings, pixel, (side, count..most), None);
        (round.and(&rest).pixel(), most)
    }

    /// Camera samples `range` of pixel `(x, y)` (of a grid of `side`²), each weighing
    /// 1/`range.len()`: their sums and how their luminance spreads. Their receivers go to
    /// `receivers`; with `None` (an edge's samples past its first round) none gathers.
    ///
    /// The samples' direct light shares out one set of the pixel's light points
    /// ([`LightShare`]): a range that starts at 0 takes the first set, any other the second,
    /// so that an edge's first round and the rest of its samples each stratify their own.
    fn trace_samples(
        &self,
        ctx: &Tracer,
        camera: &Camera,
        settings: &PrimarySettings,
        (x, y): (u32, u32),
        (side, range): (u32, Range<u32>),
        receivers: Option<&mut Vec<Receiver>>,
    ) -> Samples {
        let pixel = y * self.width + x;
        let count = range.len() as u32;
        let weight = Rgb::splat(1.0 / count as f32);
        let mut per_pixel = Sampler::new(settings.seed, u64::from(pixel), u64::MAX);
        let scramble = per_pixel.next_scramble();
        // The pixel's two sets of light points, each shared out among some of its samples.
        let first_light = (per_pixel.next_scramble(), per_pixel.next_u32());
        let light = if range.start == 0 {
            first_light
        } else {
            (per_pixel.next_scramble(), per_pixel.next_u32())
        };
        let mut out = Samples {
            count,
            mean: PrimarySample {
                depth: f32::INFINITY,
                ..PrimarySample::default()
            },
            spread: Spread::EMPTY,
            hits: 0,
        };
        let mut quarters_gathered = [false; 4];
        let by_quarter = side == EDGE_SIDE || (side == SMOOTH_SIDE && settings.smooth_quarters);
        let gathers = receivers.is_some();
        let mut none = Vec::new();
        let receivers = receivers.unwrap_or(&mut none);
        for s in range.clone() {
            let mut sampler = Sampler::new(settings.seed, u64::from(pixel), u64::from(s));
            let jitter = if side == 1 {
                Vec2::splat(0.5)
            } else {
                sobol02(s, scramble)
            };
            let (o, d) = camera.generate_ray(Vec2::new(x as f32, y as f32) + jitter);
            // On an edge (and with `smooth_quarters` on a smooth mirror or glass) the first
            // sample in each quarter of the pixel gathers, for the quarter; elsewhere the
            // first gathers for the whole pixel.
            let quarter = usize::from(jitter.x >= 0.5) + 2 * usize::from(jitter.y >= 0.5);
            let gather_weight = match by_quarter {
                true => (!std::mem::replace(&mut quarters_gathered[quarter], true))
                    .then_some(Rgb::splat(0.25)),
                false => (s == 0).then_some(Rgb::ONE),
            };
            let cs = CameraSample {
                o,
                d,
                pixel,
                weight,
                gather_weight: gather_weight.filter(|_| gathers),
                quarter: by_quarter.then_some(quarter as u8),
                light: LightShare::of_sample(settings.light_samples, s - range.start, count, light),
            };
            let r = trace_primary(ctx, settings, cs, &mut sampler, receivers);
            out.spread = out.spread.add(luminance(r.direct) * count as f32);
            out.mean.direct += r.direct;
            out.mean.albedo += r.albedo * weight;
            out.mean.normal += r.normal * weight;
            out.mean.depth = out.mean.depth.min(r.depth);
            out.hits += u32::from(r.depth.is_finite());
        }
        out
    }
}

/// What [`PixelSampling::trace_samples`] found.
struct Samples {
    /// How many samples were taken.
    count: u32,
    /// Emission and direct light, albedo and normal: the samples' mean (each weighed
    /// 1/`count`; the normal not yet made unit); depth: the nearest.
    mean: PrimarySample,
    /// How the samples' luminance (emission and direct light) spreads.
    spread: Spread,
    /// How many samples hit the scene.
    hits: u32,
}

impl Samples {
    /// These samples and `more` as one set, each weighing its share of the two counts.
    fn and(&self, more: &Samples) -> Samples {
        let count = self.count + more.count;
        let (a, b) = (
            self.count as f32 / count as f32,
            more.count as f32 / count as f32,
        );
        Samples {
            count,
            mean: PrimarySample {
                direct: self.mean.direct * a + more.mean.direct * b,
                albedo: self.mean.albedo * a + more.mean.albedo * b,
                normal: self.mean.normal * a + more.mean.normal * b,
                depth: self.mean.depth.min(more.mean.depth),
                alpha: 0.0,
            },
            spread: Spread::EMPTY,
            hits: self.hits + more.hits,
        }
    }

    /// The pixel's value from these samples: the normal made unit, the coverage.
    fn pixel(&self) -> PrimarySample {
        PrimarySample {
            normal: self.mean.normal.normalize_or_zero(),
            alpha: self.hits as f32 / self.count as f32,
            ..self.mean
        }
    }
}

/// The least, greatest and summed luminance of some samples, kept as they come (no list).
#[derive(Clone, Copy, Debug)]
struct Spread {
    lo: f32,
    hi: f32,
    sum: f32,
    count: u32,
}

impl Spread {
    const EMPTY: Spread = Spread {
        lo: f32::INFINITY,
        hi: 0.0,
        sum: 0.0,
        count: 0,
    };

    fn of(values: &[f32]) -> Spread {
        values.iter().fold(Spread::EMPTY, |s, &v| s.add(v))
    }

    fn add(self, v: f32) -> Spread {
        Spread {
            lo: self.lo.min(v),
            hi: self.hi.max(v),
            sum: self.sum + v,
            count: self.count + 1,
        }
    }

    /// Whether the values spread wide against their mean: the spread, squared, exceeds
    /// [`EDGE_SPREAD`] of the mean's square. Relative, so a scene lit 2^k times as brightly
    /// is sampled alike.
    fn wide(&self) -> bool {
        let mean = self.sum / self.count.max(1) as f32;
        let spread = self.hi - self.lo;
        spread * spread > EDGE_SPREAD * mean * mean
    }
}

/// Whether an edge pixel's first round of samples, whose luminances spread as `first` and of
/// which `hits` of `round` hit the scene, leaves its mean uncertain: some samples miss the
/// scene while others hit (the coverage is an edge too), or their luminance spreads wide
/// ([`Spread::wide`]). An emitter's outline (radiance 18 beside 0.5) always takes the other
/// rounds; an edge between two lit walls of similar brightness does not.
fn needs_more(first: &Spread, hits: u32, round: u32) -> bool {
    (hits != 0 && hits != round) || first.wide()
}

/// Whether two neighbouring hits lie on one surface: the same mesh, normals within 25°, depths
/// within 5 % of the nearer.
fn same_surface(m0: u32, n0: Vec3, d0: f32, m1: u32, n1: Vec3, d1: f32) -> bool {
    m0 == m1 && n0.dot(n1) >= SAME_NORMAL && (d0 - d1).abs() <= SAME_DEPTH * d0.min(d1)
}

/// Whether two neighbours' chains end alike: both rough, or both smooth with the same
/// branches ending on one surface each.
fn same_ends(a: Option<&[ChainEnd]>, b: Option<&[ChainEnd]>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.len() == b.len()
                && a.iter().zip(b).all(|(e, f)| {
                    e.chain == f.chain
                        && same_surface(e.mesh, e.normal, e.depth, f.mesh, f.normal, f.depth)
                })
        }
        _ => false,
    }
}

/// The rough hits at the ends of the specular chain of the centre ray `(o, d)` of `pixel`,
/// traced as the primary pass traces a camera sample (every branch, to the same depth and
/// weight cut-offs), without its direct light; sorted by chain signature. And the light it
/// sees emitted along the way.
fn chain_ends(
    ctx: &Tracer,
    settings: &PrimarySettings,
    o: Vec3,
    d: Vec3,
    pixel: u32,
) -> (Vec<ChainEnd>, Rgb) {
    let sample = CameraSample {
        o,
        d,
        pixel,
        weight: Rgb::ONE,
        gather_weight: Some(Rgb::ONE),
        quarter: None,
        light: LightShare::NONE,
    };
    // A stream of its own: the camera samples' are keyed by their index.
    let mut sampler = Sampler::new(settings.seed, u64::from(pixel), u64::MAX - 1);
    let mut receivers: Vec<Receiver> = Vec::new();
    // The ends' own receivers, with every depth allowed: an end past max_depth is still
    // what the pixel shows.
    let unlimited = PrimarySettings {
        max_depth: -1,
        ..*settings
    };
    let emitted = trace_primary(ctx, &unlimited, sample, &mut sampler, &mut receivers).direct;
    let mut ends: Vec<ChainEnd> = receivers
        .iter()
        .map(|r| ChainEnd {
            chain: r.chain,
            mesh: r.mesh,
            normal: r.frame.n,
            depth: (r.p - o).length(),
        })
        .collect();
    ends.sort_by_key(|e| e.chain);
    (ends, emitted)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `count` samples whose mean direct light, albedo and normal are `value`, `hits` of
    /// them on the scene at `depth`.
    fn samples(count: u32, value: f32, normal: Vec3, hits: u32, depth: f32) -> Samples {
        Samples {
            count,
            mean: PrimarySample {
                direct: Rgb::splat(value),
                albedo: Rgb::splat(value),
                normal,
                depth,
                alpha: 0.0,
            },
            spread: Spread::EMPTY,
            hits,
        }
    }

    /// An edge's round of 16 and the other 48 make the mean of all 64, each sample weighing
    /// 1/64: direct light and albedo by count, the normal's sum made unit, the nearest depth,
    /// the coverage over all 64.
    #[test]
    fn an_edges_round_and_its_rest_weigh_by_their_counts() {
        let round = samples(16, 4.0, Vec3::X, 16, 2.0);
        let rest = samples(48, 0.5, Vec3::Y, 40, 3.0);
        let all = round.and(&rest);
        assert_eq!(all.count, 64);
        let mean = all.pixel();
        let expected = (16.0 * 4.0 + 48.0 * 0.5) / 64.0;
        assert!((mean.direct - Rgb::splat(expected)).abs().max_element() < 1e-6);
        assert!((mean.albedo - Rgb::splat(expected)).abs().max_element() < 1e-6);
        let normal = (Vec3::X * 0.25 + Vec3::Y * 0.75).normalize();
        assert!((mean.normal - normal).length() < 1e-6);
        assert_eq!(mean.depth, 2.0);
        assert_eq!(mean.alpha, 56.0 / 64.0);
        // A round alone is its own mean.
        let alone = round.pixel();
        assert_eq!((alone.direct, alone.alpha), (Rgb::splat(4.0), 1.0));
    }

    fn end(chain: u64, mesh: u32, depth: f32) -> ChainEnd {
        ChainEnd {
            chain,
            mesh,
            normal: Vec3::Z,
            depth,
        }
    }

    /// Chains end alike when every branch ends on one surface; a branch more or less, another
    /// mesh, or a depth step of more than 5 % is an edge.
    #[test]
    fn chains_end_alike_on_one_surface_only() {
        let a = [end(1, 3, 2.0), end(7, 4, 3.0)];
        assert!(same_ends(
            Some(&a),
            Some(&[end(1, 3, 2.05), end(7, 4, 3.1)])
        ));
        assert!(!same_ends(Some(&a), Some(&a[..1])), "a branch less");
        assert!(!same_ends(
            Some(&a),
            Some(&[end(1, 3, 2.0), end(7, 5, 3.0)])
        ));
        assert!(!same_ends(
            Some(&a),
            Some(&[end(1, 3, 2.2), end(7, 4, 3.0)])
        ));
        assert!(!same_ends(
            Some(&a),
            Some(&[end(1, 3, 2.0), end(8, 4, 3.0)])
        ));
        assert!(
            !same_ends(Some(&a), None),
            "a mirror beside a rough surface"
        );
        assert!(same_ends(None, None));
        assert!(same_ends(Some(&[]), Some(&[])), "two chains lost alike");
    }

    /// An edge's first round goes on where its samples spread wide against their mean: an
    /// emitter's outline (18 beside 0.5), a wall beside a dark one (0.5 beside 0.05), a
    /// coverage edge; not two walls of about one brightness, nor a round of equal samples.
    #[test]
    fn a_round_goes_on_where_its_samples_disagree() {
        let round = |a: f32, b: f32| -> Spread {
            let values: Vec<f32> = (0..16).map(|i| if i < 8 { a } else { b }).collect();
            Spread::of(&values)
        };
        for (first, hits, more, what) in [
            (round(18.0, 0.5), 16, true, "an emitter's outline"),
            (round(0.5, 0.05), 16, true, "a lit wall beside a dark one"),
            (round(0.5, 0.4), 16, false, "two walls of one brightness"),
            (round(0.3, 0.3), 16, false, "equal samples"),
            (round(0.3, 0.3), 12, true, "some samples miss the scene"),
            (round(0.0, 0.0), 0, false, "all miss, a black sky"),
        ] {
            assert_eq!(needs_more(&first, hits, 16), more, "{what}");
        }
        // The outline test on the centre rays' emitted light, by the same rule.
        let wide = |v: &[f32]| Spread::of(v).wide();
        assert!(wide(&[18.0, 0.0]) && wide(&[0.0, 1.0]));
        assert!(!wide(&[0.0, 0.0]) && !wide(&[1.0, 1.1]));
    }
}
