//! Direct light at surfels by ray tracing (docs/design.md §5.2, docs/method.md §5.1).
//!
//! Each surfel draws `samples` emitter samples, chosen by power and placed on the emitter by a
//! scrambled (0, 2)-sequence (see [`crate::sampler::sobol02`]), uniformly over the solid angle
//! of a near triangle (a bounded estimator by an emitting wall's edge, see
//! [`crate::geometry::spherical_triangle`]), each with a shadow ray. The same
//! samples serve every outgoing direction of the surfel, so its radiance map is one consistent
//! function rather than independent noise per texel:
//!
//! L(ω) = (1/K) Σₖ f(ω, ωₖ) |cos θₖ| Lₑ,ₖ / pₖ   for each texel centre ω of the octahedral map,
//!
//! except for near-specular BSDFs (α below [`NEAR_SPECULAR_ALPHA`]): a texel centre then sees
//! almost none of the K sample lobes, and the map is a few spikes (cbox-mirror's α = 0.001 box:
//! relMSE 7.1e-3 with 128 samples, 1.1e-2 with 64, 1.8e-2 with 32). Their samples are binned
//! into the BSDF operator's grid as mean radiance per texel, and the operator, which integrates
//! f over texel pairs, gives the map (D = V·C, as in a bounce). For wider lobes point values are
//! better: through the operator the glass of cbox-glossy (α = 0.02) blurred the caustic under
//! it (relMSE +16 %). The K samples are evaluated as lanes ([`Bsdf::eval_lanes`]: the same
//! values, several at a time), 2.3–2.7 times faster than one by one on the glass scenes.
//!
//! For diffuse surfels, which store RGB only, the irradiance E = (1/K) Σₖ max(0, n·ωₖ) Lₑ,ₖ/pₖ
//! (the outgoing radiance is then ρE/π). The K samples draw among the emitters other than
//! the delta lights (point, spot, directional), and each of those (up to
//! [`EXACT_DELTA_LIGHTS`](crate::emitters::EXACT_DELTA_LIGHTS)) joins them once, exactly, with
//! its own shadow ray ([`Draw::WithoutDelta`]): drawn among the K, a point light beside an area
//! light took one sample more or fewer from surfel to surfel, and its light varied by that
//! much. With many point and spot lights, a light tree gives each surfel its lightcut instead
//! (see [`super::lightcuts`]); its clusters join the samples.

use super::lightcuts::LightTree;
use crate::accel::Accel;
use crate::bake::bounce::bsdf_operator::SurfelOperator;
use crate::bsdf::{Bsdf, TransportMode};
use crate::emitters::{Draw, EmitterSample, EmitterSampler};
use crate::geometry::frame::Frame;
use crate::geometry::offset::offset_origin;
use crate::haar::texel_directions;
use crate::sampler::{sobol02, Sampler};
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::surfels::Surfel;
use glam::{Vec3, Vec3A};

/// What direct lighting needs of a scene.
pub struct DirectLight<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its triangles' BVH (for shadow rays).
    pub accel: &'a Accel,
    /// Its emitters.
    pub emitters: &'a EmitterSampler,
    /// Emitter samples per surfel.
    pub samples: u32,
    /// Seed of the emitter samples.
    pub seed: u64,
    /// Point and spot lights through Lightcuts (then `emitters` must leave them out, see
    /// [`EmitterSampler::with_punctual`]); `None` samples them with the other emitters.
    pub light_tree: Option<&'a LightTree>,
    /// Largest lightcut, in clusters.
    pub max_cut: usize,
}

/// BSDFs narrower than this (α) take their maps' direct light through their operator (see the
/// module docs).
pub const NEAR_SPECULAR_ALPHA: f32 = 0.01;

/// Lightcuts' relative error target (docs/design.md §5.2).
pub(crate) const LIGHTCUT_ERROR: f32 = 0.02;

/// One unoccluded emitter sample as seen from a surfel.
struct Arrival {
    /// Unit direction towards the emitter.
    wi: Vec3,
    /// Its share of the estimate: Lₑ / (p K) for one of K samples, a delta light's light, or a
    /// lightcut cluster's
    /// irradiance on a surface facing it.
    value: Rgb,
}

impl DirectLight<'_> {
    /// The visible emitter samples of surfel number `id`.
    fn arrivals(&self, s: &Surfel, id: u64) -> Vec<Arrival> {
        let (p, err) = s.position_with_error(self.scene);
        let ng = Vec3A::from(s.n);
        let mut r = Sampler::new(self.seed, id, 0);
        let scramble = r.next_scramble();
        let shift = r.next_1d();
        let k = self.samples;
        let mut out: Vec<Arrival> = (0..k)
            .filter_map(|i| {
                // Emitter choice stratified over the K samples, the point by the (0, 2)-sequence.
                let u_sel = ((i as f32 + shift) / k as f32).min(1.0 - f32::EPSILON);
                let es: EmitterSample = self.emitters.sample_solid_angle(
                    self.scene,
                    Vec3::from(p),
                    (u_sel, sobol02(i, scramble)),
                    Draw::WithoutDelta,
                )?;
                let origin = Vec3::from(offset_origin(p, err, ng, Vec3A::from(es.wi)));
                es.visible_from(self.accel, None, origin)
                    .then_some(Arrival {
                        wi: es.wi,
                        value: es.value / k as f32,
                    })
            })
            .collect();
        // The delta lights, each once and exactly (`Draw::WithoutDelta`).
        for es in self
            .emitters
            .delta_lights(self.scene, Vec3::from(p), Draw::WithoutDelta)
        {
            let origin = Vec3::from(offset_origin(p, err, ng, Vec3A::from(es.wi)));
            if es.visible_from(self.accel, None, origin) {
                out.push(Arrival {
                    wi: es.wi,
                    value: es.value,
                });
            }
        }
        if let Some(tree) = self.light_tree {
            let origin = Vec3::from(offset_origin(p, err, ng, ng));
            let (cut, _) = tree.cut(
                self.accel,
                Vec3::from(p),
                origin,
                s.n,
                LIGHTCUT_ERROR,
                self.max_cut,
            );
            out.extend(cut.into_iter().map(|c| Arrival {
                wi: c.wi,
                value: c.value,
            }));
        }
        out
    }

    /// Irradiance on the front face of surfel `id` (for diffuse surfels), the cosine taken
    /// to its shading normal `shading` (`s.n` unless a normal map tilts it).
    pub fn irradiance(&self, s: &Surfel, shading: Vec3, id: u64) -> Rgb {
        self.arrivals(s, id)
            .iter()
            .map(|a| a.value * shading.dot(a.wi).max(0.0))
            .fold(Rgb::ZERO, |acc, x| acc + x)
    }

    /// The shading frame around `shading` and the visible emitter samples of surfel `id` in
    /// it: each one's local direction and value.
    fn local_arrivals(&self, s: &Surfel, shading: Vec3, id: u64) -> (Frame, Vec<(Vec3, Rgb)>) {
        let frame = Frame::from_normal(shading);
        let arrivals = self
            .arrivals(s, id)
            .into_iter()
            .map(|a| (frame.to_local(a.wi), a.value))
            .collect();
        (frame, arrivals)
    }

    /// [`DirectLight::radiance_map`] of a near-specular BSDF, through its operator `op`: the
    /// emitter samples binned into the operator's grid, D = V·C, and the result read onto the
    /// map by nearest texel, as a bounce turns gathered light into a map.
    pub(crate) fn radiance_map_through(
        &self,
        (s, shading): (&Surfel, Vec3),
        id: u64,
        op: &SurfelOperator,
        levels: u32,
    ) -> Vec<Rgb> {
        let (frame, arrivals) = self.local_arrivals(s, shading, id);
        let incident = op.shared.incident(arrivals.into_iter());
        op.sphere_map(&incident, &op.shared.map_texels(frame, levels))
    }

    /// Outgoing radiance of surfel `id` with BSDF `bsdf` at the centre of every texel of the
    /// `2^levels × 2^levels` octahedral map (row-major), over the whole sphere; the BSDF's
    /// frame is around the shading normal `shading`.
    pub fn radiance_map(
        &self,
        (s, shading): (&Surfel, Vec3),
        id: u64,
        bsdf: &Bsdf,
        levels: u32,
    ) -> Vec<Rgb> {
        let (frame, arrivals) = self.local_arrivals(s, shading, id);
        // The arrivals in lanes, evaluated several at a time (the same values).
        let lanes = [0, 1, 2].map(|c| arrivals.iter().map(|(wi, _)| wi[c]).collect::<Vec<f32>>());
        let lanes: [&[f32]; 3] = [&lanes[0], &lanes[1], &lanes[2]];
        let mut values = Vec::with_capacity(arrivals.len());
        texel_directions(levels)
            .iter()
            .map(|w| {
                bsdf.eval_lanes(
                    frame.to_local(*w),
                    lanes,
                    TransportMode::Radiance,
                    &mut values,
                );
                values
                    .iter()
                    .zip(&arrivals)
                    .map(|(f, (_, value))| *f * *value)
                    .fold(Rgb::ZERO, |acc, x| acc + x)
            })
            .collect()
    }
}
