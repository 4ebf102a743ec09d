//! What a bake is asked for: the quality presets and [`BakeSettings`], which own their
//! defaults and refuse what is out of range.

use super::bounce::BounceSettings;

/// Quality presets: surfels and emitter samples per surfel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    Draft,
    Preview,
    Final,
    Ultra,
}

impl Quality {
    /// The preset's name on the command line and in reports.
    pub fn name(self) -> &'static str {
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
    pub fn points(self) -> usize {
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
    pub fn light_samples(self) -> u32 {
        match self {
            Quality::Draft => 64,
            Quality::Preview => 32,
            Quality::Final => 256,
            Quality::Ultra => 512,
        }
    }
}

/// Everything that determines a bake's result (and so goes into the cache's content hash).
#[derive(Clone, Debug, PartialEq)]
pub struct BakeSettings {
    pub points: usize,
    pub light_samples: u32,
    /// Relative wavelet threshold (dimensionless).
    pub tau: f32,
    /// Hierarchical coding split level; `None`: three levels above the deepest leaves, as the
    /// thesis's 20 of about 23 levels.
    pub split_level: Option<u32>,
    pub seed: u64,
    /// Largest lightcut (clusters) when a light tree is used.
    pub max_cut: usize,
    /// Indirect bounces after the direct light (none: a direct-only cache).
    pub bounces: BounceSettings,
    /// Surfels per unit area of the named materials' meshes relative to the others (1), in
    /// the order given; a material named twice takes its last factor. Finer glass sharpens
    /// the caustics it casts (docs/bounces.md measures it), at the cost of its surfels.
    pub surfel_density: Vec<(String, f32)>,
}

impl BakeSettings {
    pub fn from_quality(q: Quality) -> Self {
        BakeSettings {
            points: q.points(),
            light_samples: q.light_samples(),
            tau: 2e-3,
            split_level: None,
            seed: 0,
            max_cut: 1000,
            bounces: BounceSettings::exactly(0),
            surfel_density: Vec::new(),
        }
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
