//! What a bake is asked for: the quality presets and [`BakeSettings`], which own their
//! defaults and refuse what is out of range.

use super::bounce::BounceSettings;
use crate::error::Result;
use crate::validate::{in_range, require, require_positive};

/// Quality presets: surfels and emitter samples per surfel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Quality {
    /// The fastest: for blocking and checking a scene.
    Draft,
    /// The default: `wpbgi bake`, the plugin and Python bake at it unless told otherwise.
    #[default]
    Preview,
    /// For final frames.
    Final,
    /// For stills and references.
    Ultra,
}

impl Quality {
    /// Every preset, from the fastest to the finest (the plugin's and Python's numbering).
    pub const ALL: [Quality; 4] = [
        Quality::Draft,
        Quality::Preview,
        Quality::Final,
        Quality::Ultra,
    ];

    /// The preset's name on the command line and in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Quality::Draft => "draft",
            Quality::Preview => "preview",
            Quality::Final => "final",
            Quality::Ultra => "ultra",
        }
    }

    /// Surfels. The preview preset (the default) takes 50 000: on the five Cornell-class
    /// scenes its relMSE is that of 100 000 within 6 % (higher on three, lower on two) in half
    /// the bake and two thirds of the render (docs/bounces.md, "The preview preset").
    pub const fn points(self) -> usize {
        match self {
            Quality::Draft => 20_000,
            Quality::Preview => 50_000,
            Quality::Final => 500_000,
            Quality::Ultra => 2_000_000,
        }
    }

    /// Emitter samples per surfel. Fewer per surfel as surfels grow denser: the render's
    /// gather averages many neighbours, and the error follows the spacing (measured at
    /// 100 000 surfels: 32 samples give the relMSE of 128 on the five Cornell-class scenes,
    /// within 1 %; at 20 000, 32 instead of 64 cost the caustic 8 %; at 50 000, 64 gave
    /// cbox-glossy and cbox-mirror no lower error than 32).
    pub const fn light_samples(self) -> u32 {
        match self {
            Quality::Draft => 64,
            Quality::Preview => 32,
            Quality::Final => 256,
            Quality::Ultra => 512,
        }
    }
}

/// Everything that determines a bake's result (and so goes into the cache's content hash).
/// Start from a preset ([`BakeSettings::preset`], or [`Default`]: the preview preset with
/// automatic bounces, what `wpbgi bake` does) and change fields; [`BakeSettings::validate`]
/// (which the bake calls first) refuses a field out of range, naming it.
#[derive(Clone, Debug, PartialEq)]
pub struct BakeSettings {
    /// Surfels, 1 to 2³² − 1 (the tree numbers them in 32 bits).
    pub points: usize,
    /// Emitter samples per surfel, at least 1.
    pub light_samples: u32,
    /// Relative wavelet threshold (dimensionless), in [0, 1): coefficients below this
    /// fraction of their function's norm are dropped.
    pub tau: f32,
    /// Hierarchical coding split level; `None`: three levels above the deepest leaves, as the
    /// thesis's 20 of about 23 levels. A level at or past the tree's depth means the level
    /// above its deepest leaves (the tree's depth is known only once it is built).
    pub split_level: Option<u32>,
    /// Seed of every random stream: one bake per seed, byte for byte.
    pub seed: u64,
    /// Largest lightcut (clusters) when a light tree is used, at least 1.
    pub max_cut: usize,
    /// Indirect bounces after the direct light (none: a direct-only cache).
    pub bounces: BounceSettings,
    /// Surfels per unit area of the named materials' meshes relative to the others (1), in
    /// the order given; a material named twice takes its last factor. Finer glass sharpens
    /// the caustics it casts (docs/bounces.md measures it), at the cost of its surfels.
    /// Each factor is a positive number; each name must be a material of the scene (checked
    /// by the bake, which has the scene).
    pub surfel_density: Vec<(String, f32)>,
}

impl Default for BakeSettings {
    fn default() -> Self {
        BakeSettings::preset(Quality::default())
    }
}

impl BakeSettings {
    /// The settings of preset `q`: its surfels and light samples, automatic bounces, and the
    /// defaults of every other field.
    pub const fn preset(q: Quality) -> Self {
        BakeSettings {
            points: q.points(),
            light_samples: q.light_samples(),
            tau: 2e-3,
            split_level: None,
            seed: 0,
            max_cut: 1000,
            bounces: BounceSettings::auto(),
            surfel_density: Vec::new(),
        }
    }

    /// These settings with no indirect bounces: a cache of direct light only.
    pub fn direct_only(self) -> Self {
        BakeSettings {
            bounces: BounceSettings::NONE,
            ..self
        }
    }

    /// Refuse a field out of range, in a sentence that names it (the bake calls this first).
    pub fn validate(&self) -> Result<()> {
        const S: &str = "BakeSettings";
        require(
            self.points >= 1 && u32::try_from(self.points).is_ok(),
            S,
            "points",
            self.points,
            "between 1 and 4294967295",
        )?;
        require_positive(S, "light_samples", self.light_samples as u64)?;
        require(
            in_range(self.tau, 0.0, 1.0, false),
            S,
            "tau",
            self.tau,
            "a number in [0, 1)",
        )?;
        require_positive(S, "max_cut", self.max_cut as u64)?;
        for (name, w) in &self.surfel_density {
            require(
                w.is_finite() && *w > 0.0,
                S,
                "surfel_density",
                format_args!("{w} for material \"{name}\""),
                "a positive number for each material",
            )?;
        }
        self.bounces.validate()
    }

    /// The settings [`BakeSettings::to_json`] wrote (a cache's), or the field that is missing
    /// or malformed. The transport's memory budget, which changes no cache, is the default.
    pub fn from_json(json: &serde_json::Value) -> std::result::Result<BakeSettings, String> {
        let field =
            |v: &serde_json::Value, name: &str| -> std::result::Result<serde_json::Value, String> {
                v.get(name).cloned().ok_or_else(|| format!("no \"{name}\""))
            };
        let uint = |v: &serde_json::Value, name: &str| {
            field(v, name)?
                .as_u64()
                .ok_or_else(|| format!("\"{name}\" is not a whole number"))
        };
        let float = |v: &serde_json::Value, name: &str| {
            field(v, name)?
                .as_f64()
                .map(|x| x as f32)
                .ok_or_else(|| format!("\"{name}\" is not a number"))
        };
        let narrow =
            |x: u64, name: &str| u32::try_from(x).map_err(|_| format!("\"{name}\" is too large"));
        let bounces = field(json, "bounces")?;
        let split_level = match field(json, "split_level")? {
            serde_json::Value::Null => None,
            v => Some(narrow(
                v.as_u64().ok_or("\"split_level\" is not a whole number")?,
                "split_level",
            )?),
        };
        let surfel_density = match json.get("surfel_density") {
            None => Vec::new(),
            Some(list) => list
                .as_array()
                .ok_or("\"surfel_density\" is not a list")?
                .iter()
                .map(|pair| match pair.as_array().map(Vec::as_slice) {
                    Some([name, w]) => match (name.as_str(), w.as_f64()) {
                        (Some(name), Some(w)) => Ok((name.to_string(), w as f32)),
                        _ => Err("a \"surfel_density\" entry is not [name, factor]".to_string()),
                    },
                    _ => Err("a \"surfel_density\" entry is not [name, factor]".to_string()),
                })
                .collect::<std::result::Result<_, _>>()?,
        };
        Ok(BakeSettings {
            points: usize::try_from(uint(json, "points")?)
                .map_err(|_| "\"points\" is too large")?,
            light_samples: narrow(uint(json, "light_samples")?, "light_samples")?,
            tau: float(json, "tau")?,
            split_level,
            seed: uint(json, "seed")?,
            max_cut: usize::try_from(uint(json, "max_cut")?)
                .map_err(|_| "\"max_cut\" is too large")?,
            bounces: BounceSettings {
                max: narrow(uint(&bounces, "max")?, "max")?,
                tolerance: float(&bounces, "tolerance")?,
                operator_tau: float(&bounces, "operator_tau")?,
                view_tree: field(&bounces, "view_tree")?
                    .as_bool()
                    .ok_or("\"view_tree\" is not true or false")?,
                receiver_stride: narrow(uint(&bounces, "receiver_stride")?, "receiver_stride")?,
                transport_budget: None,
            },
            surfel_density,
        })
    }

    /// A canonical text of the settings, for the content hash and the cache's plan.
    pub fn to_json(&self) -> serde_json::Value {
        let mut json = serde_json::json!({
            "points": self.points,
            "light_samples": self.light_samples,
            "tau": self.tau,
            "split_level": self.split_level,
            "seed": self.seed,
            "max_cut": self.max_cut,
            "bounces": {
                "max": self.bounces.max,
                "tolerance": self.bounces.tolerance,
                "operator_tau": self.bounces.operator_tau,
                "view_tree": self.bounces.view_tree,
                "receiver_stride": self.bounces.receiver_stride,
            },
        });
        // Left out when uniform, so that the caches of earlier versions keep their hash.
        if !self.surfel_density.is_empty() {
            json["surfel_density"] = self
                .surfel_density
                .iter()
                .map(|(name, w)| serde_json::json!([name, w]))
                .collect();
        }
        json
    }
}
