//! What both path tracers share (the reference one in [`crate::reference`] and the final
//! render's in [`crate::render`](mod@crate::render)): the scene with its acceleration structure and emitter
//! sampler ([`Tracer`]), the description of a ray's closest hit that shading reads
//! ([`SurfaceHit`]), next-event estimation ([`Tracer::next_event`]) and the
//! multiple-importance weight ([`mis`]). Neither path tracer knows
//! the other; both build on this.
//!
//! What a path tracer calls once per vertex here (the closest hit and its surface, the
//! spawned origin, next-event estimation, an emitter's hit) is `#[inline(always)]`, as are the
//! accel's queries they make: left as calls, each handed its vectors and its result through
//! memory, written a float or two at a time and read back whole, and every such read waited
//! for the stores to retire (a failed store-to-load forwarding, a dozen cycles or more). Inlined
//! into the path's loop the values stay in registers: with the accel's packet reads written out
//! likewise, `wpbgi reference` 0.87 of the time on cbox-diffuse, the images the same bit for
//! bit (docs/benchmarks.md).

use crate::accel::{Accel, Hit, TriangleId};
use crate::bsdf::{Bsdf, TransportMode};
use crate::emitters::{Draw, EmitterSampler};
use crate::geometry::frame::Frame;
use crate::geometry::offset::{interpolate_with_error, offset_origin};
use crate::scene::{Mesh, Scene};
use crate::spectrum::Rgb;
use glam::{Vec2, Vec3, Vec3A};
use std::sync::OnceLock;

/// A scene ready to trace: its triangles' acceleration structure and its emitters' sampler,
/// built once per render.
pub struct Tracer<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its triangles' bounding volume hierarchy.
    pub accel: Accel,
    /// Its emitters, for next-event estimation.
    pub emitters: EmitterSampler,
    /// The triangles of its emitting meshes alone (see [`Tracer::may_reach_emitter`]), built
    /// on its first use: the path tracer and the bake never ask.
    emissive: OnceLock<Accel>,
}

impl<'a> Tracer<'a> {
    /// Build the acceleration structure and the emitter sampler of `scene`.
    pub fn new(scene: &'a Scene) -> Self {
        Tracer {
            scene,
            accel: Accel::build(scene),
            emitters: EmitterSampler::new(scene),
            emissive: OnceLock::new(),
        }
    }

    /// Whether the ray from `origin` along `dir` may find light where it first meets the
    /// scene: false only when it meets no emitting triangle at all and there is no
    /// environment, so that its closest hit, whatever it is, emits nothing. A test against
    /// the few emitting triangles, instead of the whole scene's closest hit and surface, for
    /// the BSDF samples of direct light (most of which miss a small light). The closest hit
    /// on an emitter is a hit of the same watertight test here, so no light is lost.
    pub fn may_reach_emitter(&self, origin: Vec3, dir: Vec3) -> bool {
        self.scene.environment.is_some()
            || self
                .emissive
                .get_or_init(|| Accel::build_over(self.scene, |m| self.scene.emits(m)))
                .occluded(origin, dir, 0.0, f32::INFINITY)
    }

    /// Next-event estimation at `hit`, shaded by `bsdf` and seen from local direction
    /// `view`: one emitter sample (drawn with `u_sel` and `u`), its light reflected towards
    /// `view` times `throughput`, weighted by the power heuristic against the BSDF samples
    /// that could find the same emitter (a delta light fully). Zero where it is occluded or
    /// the BSDF sends nothing its way.
    #[inline(always)]
    pub fn next_event(
        &self,
        hit: &SurfaceHit,
        bsdf: &Bsdf,
        view: Vec3,
        (u_sel, u): (f32, Vec2),
        throughput: Rgb,
    ) -> Rgb {
        let Some(es) = self
            .emitters
            .sample(self.scene, hit.p, (u_sel, u), Draw::All)
        else {
            return Rgb::ZERO;
        };
        let wo = hit.frame.to_local(es.wi);
        let f = bsdf.eval(view, wo, TransportMode::Radiance);
        if f == Rgb::ZERO || !es.visible_from(&self.accel, Some(hit.id()), hit.spawn(es.wi)) {
            return Rgb::ZERO;
        }
        let w = if es.delta {
            1.0
        } else {
            mis(es.pdf, bsdf.pdf(view, wo))
        };
        throughput * f * es.value * w
    }

    /// The light of an emitter that a BSDF sample of density `bsdf_pdf` (`None`: a delta lobe
    /// or the camera) hits at `hit` along `w`, times `throughput`, weighted by the power
    /// heuristic against the next-event estimation that could have sampled it (fully for
    /// `None`). Zero where `hit` emits nothing.
    #[inline(always)]
    pub fn emission_hit(
        &self,
        hit: &SurfaceHit,
        w: Vec3,
        bsdf_pdf: Option<f32>,
        throughput: Rgb,
    ) -> Rgb {
        let material = &self.scene.materials[self.scene.meshes[hit.mesh as usize].material];
        if material.emission.is_none() {
            return Rgb::ZERO;
        }
        let le = material.emission_at(&self.scene.textures, hit.uv, hit.frame.to_local(-w).z > 0.0);
        if le == Rgb::ZERO {
            return Rgb::ZERO;
        }
        let weight = bsdf_pdf.map_or(1.0, |pdf| {
            mis(
                pdf,
                self.emitters
                    .pdf_hit(hit.mesh, hit.triangle, hit.t, w, hit.ng, Draw::All),
            )
        });
        throughput * le * weight
    }

    /// The environment's light along `w` for a ray that escaped after a BSDF sample of
    /// density `bsdf_pdf` (`None`: a delta lobe or the camera), weighted as
    /// [`Tracer::emission_hit`] weighs an emitter's. Zero without an environment.
    pub fn environment_hit(&self, w: Vec3, bsdf_pdf: Option<f32>, throughput: Rgb) -> Rgb {
        let Some(env) = &self.scene.environment else {
            return Rgb::ZERO;
        };
        let weight = bsdf_pdf.map_or(1.0, |pdf| {
            mis(pdf, self.emitters.pdf_environment(self.scene, w, Draw::All))
        });
        throughput * env.radiance(w) * weight
    }
}

/// A ray–surface intersection with what shading needs.
pub struct SurfaceHit {
    /// The hit point (world space).
    pub p: Vec3,
    /// Rounding bound of `p`.
    pub err: Vec3,
    /// Unit geometric normal of the front face (counter-clockwise winding).
    pub ng: Vec3,
    /// Shading frame around the interpolated normal (or `ng` for flat meshes), tilted by the
    /// material's normal map.
    pub frame: Frame,
    /// Texture coordinates there.
    pub uv: Vec2,
    /// The mesh hit.
    pub mesh: u32,
    /// The triangle hit, within the mesh.
    pub triangle: u32,
    /// Distance along the ray (in units of its direction's length).
    pub t: f32,
}

impl SurfaceHit {
    /// The triangle hit.
    pub fn id(&self) -> TriangleId {
        (self.mesh, self.triangle)
    }

    /// A ray leaving this point along `w`, offset to the side `w` points to (off the plane
    /// of triangle [`SurfaceHit::id`]).
    #[inline(always)]
    pub fn spawn(&self, w: Vec3) -> Vec3 {
        Vec3::from(offset_origin(
            Vec3A::from(self.p),
            Vec3A::from(self.err),
            Vec3A::from(self.ng),
            Vec3A::from(w),
        ))
    }
}

/// Trace a ray and describe the closest hit.
pub fn intersect(ctx: &Tracer, o: Vec3, d: Vec3) -> Option<SurfaceHit> {
    intersect_within(ctx, o, d, f32::INFINITY)
}

/// [`intersect`] along a unit `d` (as `Vec3::normalize` leaves it), for a ray spawned off
/// triangle `leaving` ([`SurfaceHit::spawn`]; `None` where it was not, as a camera ray): the
/// same hit, found without normalising `d` again or deciding in double precision that the
/// ray does not meet the triangle it leaves ([`Accel::closest_hit_unit`]).
#[inline(always)]
pub fn intersect_leaving(
    ctx: &Tracer,
    leaving: Option<TriangleId>,
    o: Vec3,
    d: Vec3,
) -> Option<SurfaceHit> {
    let hit = ctx
        .accel
        .closest_hit_unit(leaving, o, d, 0.0, f32::INFINITY)?;
    Some(surface_hit(ctx, geometric_hit(hit)))
}

/// [`intersect`], for hits nearer than `t_max` (in units of `d`'s length).
pub fn intersect_within(ctx: &Tracer, o: Vec3, d: Vec3, t_max: f32) -> Option<SurfaceHit> {
    Some(surface_hit(
        ctx,
        intersect_geometry_within(ctx, o, d, t_max)?,
    ))
}

/// What shading needs of the closest hit `g`.
#[inline(always)]
fn surface_hit(ctx: &Tracer, g: GeometricHit) -> SurfaceHit {
    let GeometricHit { p, err, ng, hit } = g;
    let m = &ctx.scene.meshes[hit.mesh as usize];
    let ns = m.normal_at(hit.triangle, hit.b).unwrap_or(ng);
    let uv = m.uv_at(hit.triangle, hit.b);
    let ns = match &ctx.scene.materials[m.material].normal_map {
        Some(map) => map.shading_normal(&ctx.scene.textures, m, hit.triangle, uv, ns),
        None => ns,
    };
    SurfaceHit {
        p,
        err,
        ng,
        frame: Frame::from_normal(ns),
        uv,
        mesh: hit.mesh,
        triangle: hit.triangle,
        t: hit.t,
    }
}

/// Where a ray meets the scene, without what shading needs: the point, its rounding bound,
/// the unit geometric normal and the tree's hit ([`intersect_geometry_within`]).
pub struct GeometricHit {
    /// The hit point (world space), as [`SurfaceHit::p`].
    pub p: Vec3,
    /// Rounding bound of `p`.
    pub err: Vec3,
    /// Unit geometric normal of the front face, as [`SurfaceHit::ng`].
    pub ng: Vec3,
    /// The mesh, triangle, barycentric weights and distance.
    pub hit: Hit,
}

/// [`intersect_within`]'s point and geometric normal alone, for rays that read no surface
/// (a render receiver's near field: `render::near_field`), skipping the shading normal,
/// texture coordinates and normal map; the same values bit for bit.
pub fn intersect_geometry_within(
    ctx: &Tracer,
    o: Vec3,
    d: Vec3,
    t_max: f32,
) -> Option<GeometricHit> {
    Some(geometric_hit(ctx.accel.closest_hit(o, d, 0.0, t_max)?))
}

/// The point and geometric normal of the tree's hit.
fn geometric_hit(hit: Hit) -> GeometricHit {
    let (p, err) = interpolate_with_error(hit.corners, hit.b);
    let ng = Mesh::geometric_normal(hit.corners);
    GeometricHit {
        p: Vec3::from(p),
        err: Vec3::from(err),
        ng,
        hit,
    }
}

/// Power heuristic with exponent 2.
#[inline]
pub fn mis(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && a2.is_finite() {
        a2 / (a2 + b2)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Diffuse;
    use crate::sampler::Sampler;
    use crate::scene::{Emission, Material, Mesh, Scattering};

    /// A square of half-side `side` centred at `c`, in the plane ⊥ axis `axis` (0–2), as one
    /// mesh.
    fn quad(c: Vec3, axis: usize, side: f32, material: usize) -> Mesh {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let corner = |a: f32, b: f32| {
            let mut p = c;
            p[u] += a * side;
            p[v] += b * side;
            p
        };
        Mesh {
            name: format!("quad{axis}"),
            positions: vec![
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
            ],
            normals: None,
            uvs: None,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            material,
        }
    }

    fn material(emission: Option<Emission>) -> Material {
        Material {
            name: "m".into(),
            scattering: Scattering::Explicit(Bsdf::Diffuse(Diffuse {
                reflectance: Rgb::splat(0.5),
            })),
            cutout: None,
            normal_map: None,
            emission,
        }
    }

    /// A ray whose closest hit is on an emitter always may reach one, and most rays that
    /// meet no emitter are told so: a small light over a floor, half hidden by a blocker
    /// between, seen along random rays from random points above the floor.
    #[test]
    fn rays_that_hit_an_emitter_may_reach_one() {
        let light = Emission {
            radiance: Rgb::ONE,
            texture: None,
            two_sided: true,
        };
        let scene = Scene {
            meshes: vec![
                quad(Vec3::ZERO, 1, 4.0, 0),
                quad(Vec3::new(0.0, 3.0, 0.0), 1, 0.5, 1),
                quad(Vec3::new(0.5, 2.0, 0.0), 1, 0.5, 0),
            ],
            materials: vec![material(None), material(Some(light))],
            ..Default::default()
        };
        let tracer = Tracer::new(&scene);
        let mut s = Sampler::new(4, 0, 0);
        let (mut lit, mut told_dark) = (0, 0);
        for _ in 0..20_000 {
            let (a, b) = (s.next_2d(), s.next_2d());
            let o = Vec3::new(4.0 * a.x - 2.0, 0.1 + 2.5 * a.y, 4.0 * b.x - 2.0);
            let d = crate::geometry::warp::square_to_uniform_sphere(s.next_2d());
            let emitter = tracer
                .accel
                .closest_hit(o, d, 0.0, f32::INFINITY)
                .is_some_and(|h| h.mesh == 1);
            let may = tracer.may_reach_emitter(o, d);
            assert!(may || !emitter, "ray {o} {d} hits the light");
            lit += usize::from(emitter);
            told_dark += usize::from(!may);
        }
        assert!(
            lit > 200,
            "{lit} rays hit the light: the test must see some"
        );
        assert!(
            told_dark > 10_000,
            "{told_dark} rays were told they find no light"
        );
    }
}
