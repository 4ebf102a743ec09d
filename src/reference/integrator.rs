//! The path-tracing loop for one camera sample (Mitsuba's `path` integrator).

use crate::bsdf::TransportMode;
use crate::sampler::Sampler;
use crate::spectrum::{max_component, Rgb};
use crate::trace::{intersect_leaving, Tracer};
use glam::Vec3;

/// Which paths the path tracer sums.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transport {
    /// Every path (within `max_depth`): the ground truth.
    Full,
    /// The paths the final render from a direct-only cache sums (`crate::render`), for
    /// testing it: up to `chain` vertices smoother than `smooth_below` (no next-event
    /// estimation there), then a rough vertex lit directly and by one more vertex that is
    /// itself lit directly.
    CacheOneBounce {
        /// The roughness below which a vertex continues the chain.
        smooth_below: f32,
        /// The longest chain, in vertices.
        chain: u32,
    },
}

/// Everything the integrator needs, built once per render.
pub struct RenderContext<'a> {
    /// The scene, its BVH and its emitters.
    pub tracer: Tracer<'a>,
    /// Longest path in segments (−1: unlimited), Mitsuba's `max_depth`.
    pub max_depth: i32,
    /// The depth from which Russian roulette may end a path, Mitsuba's `rr_depth`.
    pub rr_depth: u32,
    /// Which paths it sums.
    pub transport: Transport,
}

/// The largest probability with which Russian roulette continues a path (see the module docs
/// of [`crate::reference`] for why not Mitsuba's 0.95).
pub const RR_MAX: f32 = 0.999;

/// Radiance arriving at the camera along the unit ray `(o, d)`.
pub fn radiance(ctx: &RenderContext, mut o: Vec3, mut d: Vec3, sampler: &mut Sampler) -> Rgb {
    let scene = ctx.tracer.scene;
    let mut result = Rgb::ZERO;
    let mut throughput = Rgb::ONE;
    let mut eta = 1.0_f32;
    let mut depth: u32 = 0;
    // The BSDF density of the direction that led here, for MIS at emitter hits (`None` for
    // the camera ray and after a chain vertex, whose emitters count fully).
    let mut from: Option<f32> = None;
    // The triangle the ray leaves (`None` for the camera ray).
    let mut leaving = None;
    // For `Transport::CacheOneBounce`: rough vertices and chain vertices so far.
    let (mut rough, mut chain) = (0u32, 0u32);
    loop {
        let Some(si) = intersect_leaving(&ctx.tracer, leaving, o, d) else {
            // Escaped: the environment, weighted as emission is.
            result += ctx.tracer.environment_hit(d, from, throughput);
            break;
        };
        let material = &scene.materials[scene.meshes[si.mesh as usize].material];
        let wi = si.frame.to_local(-d);
        // Emission, weighted against the emitter sampling that could have found it.
        result += ctx.tracer.emission_hit(&si, d, from, throughput);
        if ctx.max_depth >= 0 && depth as i64 + 1 >= ctx.max_depth as i64 {
            break;
        }
        let bsdf = material.bsdf_at(&scene.textures, si.uv);
        let mut nee = true;
        if let Transport::CacheOneBounce {
            smooth_below,
            chain: longest,
        } = ctx.transport
        {
            // After two rough vertices only the emission found from the second counts (its
            // MIS partner is the second's next-event estimate).
            if rough == 2 {
                break;
            }
            if rough == 0 && bsdf.alpha().is_some_and(|a| a < smooth_below) {
                if chain == longest {
                    break;
                }
                chain += 1;
                nee = false;
            } else {
                rough += 1;
            }
        }
        // Next-event estimation.
        let u_sel = sampler.next_1d();
        let u_em = sampler.next_2d();
        if nee {
            result += ctx
                .tracer
                .next_event(&si, &bsdf, wi, (u_sel, u_em), throughput);
        }
        // (Else a chain vertex: the emission found next counts fully, as the render's chains.)
        // BSDF sampling.
        let u0 = sampler.next_1d();
        let u = sampler.next_2d();
        let Some(bs) = bsdf.sample(wi, u0, u, TransportMode::Radiance) else {
            break;
        };
        let wo_world = si.frame.to_world(bs.wo);
        throughput *= bs.weight;
        eta *= bs.eta;
        from = nee.then_some(bs.pdf);
        o = si.spawn(wo_world);
        leaving = Some(si.id());
        d = wo_world.normalize();
        depth += 1;
        // Russian roulette.
        let tmax = max_component(throughput);
        if !(tmax > 0.0) || !throughput.is_finite() {
            break;
        }
        if depth >= ctx.rr_depth {
            let q = (tmax * eta * eta).min(RR_MAX);
            if sampler.next_1d() >= q {
                break;
            }
            throughput /= q;
        }
    }
    if result.is_finite() {
        result
    } else {
        Rgb::ZERO
    }
}
