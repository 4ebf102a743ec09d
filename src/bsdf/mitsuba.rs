//! Parsing explicit Mitsuba BSDF descriptions (`{"type": "roughconductor", "alpha": 0.1, ...}`),
//! with Mitsuba 3.9.1's defaults and its validation rules.
//!
//! Defaults follow what Mitsuba 3.9.1 itself reports (`mi.load_dict` + `mi.traverse`), which for
//! `roughconductor.material` is `none` (a perfect mirror) and not `Cu` as older Mitsuba versions
//! and docs/design.md §4 say: the point of the explicit description is to agree with Mitsuba.

use super::ior::{conductor_ior, dielectric_ior};
use super::{Bsdf, Diffuse, Distribution, Microfacet, RoughConductor, RoughDielectric};
use crate::spectrum::Rgb;
use serde_json::{Map, Value};

/// Parse a Mitsuba BSDF dictionary. The error is one sentence naming the offending parameter.
pub fn parse_bsdf(v: &Value) -> Result<Bsdf, String> {
    let obj = v
        .as_object()
        .ok_or_else(|| "a Mitsuba BSDF must be a JSON object".to_string())?;
    let ty = obj
        .get("type")
        .and_then(Value::as_str)
        .ok_or_else(|| "a Mitsuba BSDF needs a string \"type\"".to_string())?;
    let known: &[&str] = match ty {
        "diffuse" => &["type", "reflectance"],
        "roughconductor" => &[
            "type",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "material",
            "eta",
            "k",
            "specular_reflectance",
            "sample_visible",
        ],
        "roughdielectric" => &[
            "type",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "int_ior",
            "ext_ior",
            "specular_reflectance",
            "specular_transmittance",
            "sample_visible",
        ],
        other => {
            return Err(format!(
                "unsupported Mitsuba BSDF type \"{other}\" (expected diffuse, roughconductor or roughdielectric)"
            ))
        }
    };
    if let Some(k) = obj.keys().find(|k| !known.contains(&k.as_str())) {
        return Err(format!(
            "unknown parameter \"{k}\" for Mitsuba BSDF \"{ty}\""
        ));
    }
    if obj.get("sample_visible").and_then(Value::as_bool) == Some(false) {
        return Err(
            "sample_visible = false is not supported (visible-normal sampling is always used)"
                .into(),
        );
    }
    match ty {
        "diffuse" => Ok(Bsdf::Diffuse(Diffuse {
            reflectance: rgb(obj, "reflectance", 0.5, 0.0, 1.0)?,
        })),
        "roughconductor" => {
            let distr = microfacet(obj)?;
            let has_eta = obj.contains_key("eta") || obj.contains_key("k");
            let (eta, k) = match obj.get("material") {
                Some(_) if has_eta => {
                    return Err("give either \"material\" or \"eta\"/\"k\", not both".into())
                }
                Some(m) => {
                    let name = m.as_str().ok_or("\"material\" must be a string")?;
                    conductor_ior(name)
                        .ok_or_else(|| format!("unknown conductor material \"{name}\""))?
                }
                None if has_eta => (
                    rgb(obj, "eta", 0.0, 0.0, f32::MAX)?,
                    rgb(obj, "k", 1.0, 0.0, f32::MAX)?,
                ),
                None => (Rgb::ZERO, Rgb::ONE),
            };
            Ok(Bsdf::Conductor(RoughConductor {
                distr,
                eta,
                k,
                specular_reflectance: rgb(obj, "specular_reflectance", 1.0, 0.0, f32::MAX)?,
            }))
        }
        _ => {
            let distr = microfacet(obj)?;
            let int_ior = ior(obj, "int_ior", "bk7")?;
            // Equal indices are allowed: the interface is invisible, and the scene leaves such
            // clear glass out (`Scene::drop_invisible_meshes`, docs/design.md §10).
            let ext_ior = ior(obj, "ext_ior", "air")?;
            Ok(Bsdf::Dielectric(RoughDielectric {
                distr,
                eta: int_ior / ext_ior,
                specular_reflectance: rgb(obj, "specular_reflectance", 1.0, 0.0, f32::MAX)?,
                specular_transmittance: rgb(obj, "specular_transmittance", 1.0, 0.0, f32::MAX)?,
            }))
        }
    }
}

fn microfacet(obj: &Map<String, Value>) -> Result<Microfacet, String> {
    let kind = match obj.get("distribution") {
        None => Distribution::Beckmann,
        Some(v) => {
            let s = v.as_str().ok_or("\"distribution\" must be a string")?;
            Distribution::parse(s).ok_or_else(|| {
                format!("invalid distribution \"{s}\", must be \"beckmann\" or \"ggx\"")
            })?
        }
    };
    let has_uv = obj.contains_key("alpha_u") || obj.contains_key("alpha_v");
    let (au, av) = match obj.get("alpha") {
        Some(_) if has_uv => return Err("give either \"alpha\" or \"alpha_u\"/\"alpha_v\"".into()),
        Some(_) => {
            let a = scalar(obj, "alpha", 0.1, 0.0, f32::MAX)?;
            (a, a)
        }
        None if has_uv => {
            if !(obj.contains_key("alpha_u") && obj.contains_key("alpha_v")) {
                return Err("both \"alpha_u\" and \"alpha_v\" must be given".into());
            }
            (
                scalar(obj, "alpha_u", 0.1, 0.0, f32::MAX)?,
                scalar(obj, "alpha_v", 0.1, 0.0, f32::MAX)?,
            )
        }
        None => (0.1, 0.1),
    };
    Ok(Microfacet::new(kind, au, av))
}

fn ior(obj: &Map<String, Value>, key: &str, default: &str) -> Result<f32, String> {
    let v = match obj.get(key) {
        None => return Ok(dielectric_ior(default).unwrap_or(1.0)),
        Some(v) => v,
    };
    if let Some(name) = v.as_str() {
        return dielectric_ior(name)
            .ok_or_else(|| format!("unknown index of refraction \"{name}\" for \"{key}\""));
    }
    let x = v
        .as_f64()
        .ok_or_else(|| format!("\"{key}\" must be a number or a named IOR"))? as f32;
    if !(x > 0.0 && x.is_finite()) {
        return Err(format!(
            "\"{key}\" must be a positive finite number, got {x}"
        ));
    }
    Ok(x)
}

fn scalar(
    obj: &Map<String, Value>,
    key: &str,
    default: f32,
    lo: f32,
    hi: f32,
) -> Result<f32, String> {
    let Some(v) = obj.get(key) else {
        return Ok(default);
    };
    let x = v
        .as_f64()
        .ok_or_else(|| format!("\"{key}\" must be a number (textures are not supported here)"))?
        as f32;
    if !(x >= lo && x <= hi) {
        return Err(format!("\"{key}\" = {x} is outside [{lo}, {hi}]"));
    }
    Ok(x)
}

/// A spectrum parameter: a number, an `[r, g, b]` list or `{"type": "rgb", "value": [...]}`.
fn rgb(obj: &Map<String, Value>, key: &str, default: f32, lo: f32, hi: f32) -> Result<Rgb, String> {
    let Some(v) = obj.get(key) else {
        return Ok(Rgb::splat(default));
    };
    let v = match v {
        Value::Object(o) if o.get("type").and_then(Value::as_str) == Some("rgb") => {
            o.get("value").unwrap_or(&Value::Null)
        }
        other => other,
    };
    let c = match v {
        Value::Number(n) => Rgb::splat(n.as_f64().unwrap_or(f64::NAN) as f32),
        Value::Array(a) if a.len() == 3 => {
            let mut c = [0.0_f32; 3];
            for (i, x) in a.iter().enumerate() {
                c[i] = x
                    .as_f64()
                    .ok_or_else(|| format!("\"{key}\" must hold numbers"))?
                    as f32;
            }
            Rgb::from(c)
        }
        _ => {
            return Err(format!(
                "\"{key}\" must be a number or an [r, g, b] list (textures are not supported here)"
            ))
        }
    };
    if !c.to_array().iter().all(|&x| x >= lo && x <= hi) {
        return Err(format!(
            "\"{key}\" = {c:?} has a component outside [{lo}, {hi}] or not finite"
        ));
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn defaults_are_mitsubas() {
        let Bsdf::Dielectric(d) = parse_bsdf(&json!({"type": "roughdielectric"})).unwrap() else {
            panic!()
        };
        assert!((d.eta - 1.5046 / 1.000277).abs() < 1e-6);
        assert_eq!(d.distr.kind, Distribution::Beckmann);
        assert_eq!(d.distr.alpha_u, 0.1);
        let Bsdf::Conductor(c) = parse_bsdf(&json!({"type": "roughconductor"})).unwrap() else {
            panic!()
        };
        assert_eq!((c.eta, c.k), (Rgb::ZERO, Rgb::ONE));
    }

    #[test]
    fn invalid_descriptions_are_refused() {
        for bad in [
            json!({"type": "plastic"}),
            json!({"type": "roughconductor", "distribution": "phong"}),
            json!({"type": "roughconductor", "alpha": 0.1, "alpha_u": 0.2}),
            json!({"type": "roughconductor", "alpha_u": 0.2}),
            json!({"type": "roughconductor", "material": "Au", "eta": 1.0}),
            json!({"type": "roughconductor", "material": "Unobtainium"}),
            json!({"type": "roughdielectric", "int_ior": -1.0}),
            json!({"type": "diffuse", "reflectance": [0.5, 0.5]}),
            json!({"type": "diffuse", "albedo": 0.5}),
        ] {
            assert!(parse_bsdf(&bad).is_err(), "{bad} should be refused");
        }
    }

    /// Equal indices parse (an index-matched interface, η = 1); the scene leaves such glass
    /// out (docs/design.md §10), it is not an error.
    #[test]
    fn index_matched_dielectric_parses() {
        let b = parse_bsdf(&json!({"type": "roughdielectric", "int_ior": 1.0, "ext_ior": 1.0}));
        assert!(matches!(b, Ok(Bsdf::Dielectric(d)) if d.eta == 1.0));
    }
}
