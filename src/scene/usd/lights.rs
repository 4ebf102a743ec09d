//! UsdLux lights (docs/design.md §4): rect, disk and sphere lights become emissive meshes, distant
//! lights directional lights, a dome light the environment.

use super::stage::{sample, Importer};
use crate::error::Result;
use crate::scene::material::{Emission, Material, Scattering};
use crate::scene::Environment;
use crate::scene::{Mesh, Warning};
use crate::spectrum::Rgb;
use glam::{DMat3, DMat4, DVec3, Vec3};
use openusd::gf;
use openusd::sdf;

impl Importer<'_> {
    /// A float input of light `p` (`inputs:name`, or the pre-2021 `name`).
    fn light_input(&self, p: &sdf::Path, name: &str, default: f32) -> Result<f32> {
        let prim = self.stage.prim(p.clone());
        for n in [format!("inputs:{name}"), name.to_string()] {
            let v = sample(&prim.attribute(n.as_str()), self.time)
                .map_err(|e| self.prim_err(p, format!("{n}: {e:#}")))?;
            if let Some(v) = v {
                return v
                    .cast::<f32>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| self.prim_err(p, format!("{n} must be a finite number")));
            }
        }
        Ok(default)
    }

    /// A dome light as the scene's environment: `color × intensity × 2^exposure`, times its
    /// latitude-longitude `texture:file` if it has one, oriented by its transform (its rotation
    /// only). The pole is the light's +Y axis; for `DomeLight_1`, the axis `poleAxis` names,
    /// where `scene` is the stage's up axis.
    fn dome(&mut self, p: &sdf::Path, ty: &str, radiance: Rgb, world: DMat4) -> Result<()> {
        if let Some(first) = &self.scene.environment {
            self.scene.warnings.push(Warning(format!(
                "{}: only one dome light is used ({}); left out",
                p.as_str(),
                first.name
            )));
            return Ok(());
        }
        let prim = self.stage.prim(p.clone());
        let token = |name: &str| {
            sample(&prim.attribute(name), self.time)
                .ok()
                .flatten()
                .and_then(|v| v.cast::<String>().ok())
        };
        let format = token("inputs:texture:format").unwrap_or_else(|| "automatic".into());
        let file = sample(&prim.attribute("inputs:texture:file"), self.time)
            .map_err(|e| self.prim_err(p, format!("inputs:texture:file: {e:#}")))?;
        let map = match file {
            Some(sdf::Value::AssetPath(a)) if !a.as_str().is_empty() => {
                if !matches!(format.as_str(), "automatic" | "latlong") {
                    return Err(self.prim_err(
                        p,
                        format!("texture:format {format} is not supported (latlong is)"),
                    ));
                }
                let resolved = a.resolved_path().map(str::to_string).ok_or_else(|| {
                    self.prim_err(p, format!("texture file @{}@ not found", a.as_str()))
                })?;
                let (mut map, srgb) = self.read_image(p, &resolved)?;
                if srgb {
                    map.linearise_srgb();
                }
                Some(map)
            }
            _ => None,
        };
        // The pole axis in the light's frame: +Y, or for DomeLight_1 what `poleAxis` says.
        let z_pole = ty == "DomeLight_1"
            && match token("poleAxis").as_deref() {
                Some("Z") => true,
                Some("Y") => false,
                _ => super::stage::stage_is_z_up(self.stage),
            };
        // Light frame to world, without scale: the columns orthonormalised.
        let m = DMat3::from_mat4(world);
        let x = m.x_axis.try_normalize();
        let y = x.and_then(|x| (m.y_axis - x * x.dot(m.y_axis)).try_normalize());
        let (Some(x), Some(y)) = (x, y) else {
            return Err(self.prim_err(p, "the light's transform is singular"));
        };
        let z = x.cross(y) * m.z_axis.dot(x.cross(y)).signum();
        let mut to_world = DMat3::from_cols(x, y, z);
        if z_pole {
            // The map's +Y (its pole) along the light's +Z, its +Z along the light's −Y.
            to_world *= DMat3::from_cols(DVec3::X, DVec3::Z, DVec3::NEG_Y);
        }
        self.scene.environment = Some(Environment {
            name: p.as_str().to_string(),
            map,
            scale: radiance,
            to_local: to_world.transpose().as_mat3(),
        });
        Ok(())
    }

    /// A UsdLux light: area lights become emissive meshes (radiance `intensity × color ×
    /// 2^exposure`, over the light's area with `normalize`), a distant light a directional
    /// light, a dome light the environment. Cylinder lights are not supported yet (a warning).
    pub(super) fn light(&mut self, p: &sdf::Path, ty: &str) -> Result<()> {
        let prim = self.stage.prim(p.clone());
        let intensity = self.light_input(p, "intensity", 1.0)?;
        let exposure = self.light_input(p, "exposure", 0.0)?;
        let mut color = Rgb::ONE;
        for n in ["inputs:color", "color"] {
            if let Some(v) = sample(&prim.attribute(n), self.time)
                .map_err(|e| self.prim_err(p, format!("{n}: {e:#}")))?
            {
                let c = v
                    .cast::<gf::Vec3f>()
                    .map_err(|_| self.prim_err(p, format!("{n} must be a colour")))?;
                color = Rgb::new(c.x, c.y, c.z);
                break;
            }
        }
        let normalize = ["inputs:normalize", "normalize"].iter().any(|n| {
            prim.attribute(*n)
                .get::<sdf::Value>()
                .ok()
                .flatten()
                .and_then(|v| v.cast::<bool>().ok())
                .unwrap_or(false)
        });
        let radiance = color * intensity * exposure.exp2();
        if !radiance.is_finite() || radiance.min_element() < 0.0 {
            return Err(self.prim_err(
                p,
                format!("radiance {radiance} must be finite and non-negative"),
            ));
        }
        let world = self.to_ir * self.world(p)?;
        // Local shapes; rect and disk emit towards local −Z (UsdLux), the sphere outwards.
        let (local, triangles): (Vec<DVec3>, Vec<[u32; 3]>) = match ty {
            "RectLight" => {
                let w = 0.5 * self.light_input(p, "width", 1.0)? as f64;
                let h = 0.5 * self.light_input(p, "height", 1.0)? as f64;
                (
                    vec![
                        DVec3::new(-w, -h, 0.0),
                        DVec3::new(-w, h, 0.0),
                        DVec3::new(w, h, 0.0),
                        DVec3::new(w, -h, 0.0),
                    ],
                    vec![[0, 1, 2], [0, 2, 3]],
                )
            }
            "DiskLight" => {
                let r = self.light_input(p, "radius", 0.5)? as f64;
                let n = LIGHT_SEGMENTS;
                let mut points = vec![DVec3::ZERO];
                points.extend((0..n).map(|k| {
                    // Clockwise seen from +Z, so that the front faces −Z.
                    let a = -std::f64::consts::TAU * k as f64 / n as f64;
                    DVec3::new(r * a.cos(), r * a.sin(), 0.0)
                }));
                let tris = (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
                (points, tris)
            }
            "SphereLight" => sphere(self.light_input(p, "radius", 0.5)? as f64),
            "DistantLight" => {
                let angle = self.light_input(p, "angle", 0.53)?.to_radians();
                // Radiance over a disc of `angle` (irradiance π sin²(angle/2) L), or with
                // `normalize` the irradiance itself.
                let irradiance = if normalize {
                    radiance
                } else {
                    radiance * std::f32::consts::PI * (0.5 * angle).sin().powi(2)
                };
                let direction = world
                    .transform_vector3(DVec3::NEG_Z)
                    .as_vec3()
                    .try_normalize()
                    .ok_or_else(|| self.prim_err(p, "the light's transform is singular"))?;
                self.scene.lights.push(crate::scene::PunctualLight {
                    name: p.as_str().to_string(),
                    kind: crate::scene::LightKind::Directional,
                    position: Vec3::ZERO,
                    direction,
                    intensity: irradiance,
                });
                return Ok(());
            }
            "DomeLight" | "DomeLight_1" => return self.dome(p, ty, radiance, world),
            other => {
                self.scene.warnings.push(Warning(format!(
                    "{} is a {other}, which is not supported yet; left out",
                    p.as_str()
                )));
                return Ok(());
            }
        };
        let positions: Vec<Vec3> = local
            .iter()
            .map(|&x| world.transform_point3(x).as_vec3())
            .collect();
        let mut triangles = triangles;
        if world.determinant() < 0.0 {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        let area: f32 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum();
        if !(area > 0.0 && area.is_finite()) {
            return Err(self.prim_err(p, "the light has no area"));
        }
        let radiance = if normalize { radiance / area } else { radiance };
        self.scene.materials.push(Material {
            name: p.as_str().to_string(),
            // An area light absorbs what reaches it, as Mitsuba's `area` emitters do.
            scattering: Scattering::Explicit(crate::bsdf::Bsdf::Diffuse(crate::bsdf::Diffuse {
                reflectance: Rgb::ZERO,
            })),
            cutout: None,
            normal_map: None,
            emission: Some(Emission {
                radiance,
                texture: None,
                two_sided: false,
            }),
        });
        self.scene.meshes.push(Mesh {
            name: p.as_str().to_string(),
            positions,
            normals: None,
            uvs: None,
            triangles,
            material: self.scene.materials.len() - 1,
        });
        Ok(())
    }
}

/// Segments of a disk light's polygon, and twice the rings of a sphere light's.
const LIGHT_SEGMENTS: u32 = 64;

/// A UV sphere of `radius` around the origin, counter-clockwise seen from outside.
fn sphere(radius: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let (rings, segments) = (LIGHT_SEGMENTS / 2, LIGHT_SEGMENTS);
    let mut points = vec![DVec3::new(0.0, 0.0, radius)];
    for i in 1..rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for k in 0..segments {
            let phi = std::f64::consts::TAU * k as f64 / segments as f64;
            points.push(
                radius
                    * DVec3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    ),
            );
        }
    }
    points.push(DVec3::new(0.0, 0.0, -radius));
    let at = |i: u32, k: u32| 1 + (i - 1) * segments + k % segments;
    let south = points.len() as u32 - 1;
    let mut tris = Vec::new();
    for k in 0..segments {
        tris.push([0, at(1, k), at(1, k + 1)]);
        tris.push([south, at(rings - 1, k + 1), at(rings - 1, k)]);
    }
    for i in 1..rings - 1 {
        for k in 0..segments {
            tris.push([at(i, k), at(i + 1, k), at(i + 1, k + 1)]);
            tris.push([at(i, k), at(i + 1, k + 1), at(i, k + 1)]);
        }
    }
    (points, tris)
}
