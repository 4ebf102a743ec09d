//! What the bounces did: per-bounce energies, the residual and tail, times, and the size of
//! the recorded transport. The cache records part of it; `wpbgi bake` prints it.

/// What the bounces did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BounceReport {
    /// Explicit bounces run.
    pub bounces: u32,
    /// Energy of each bounce (Σ area × luminance).
    pub energies: Vec<f64>,
    /// The last bounce's energy over the reflected total (direct and bounces).
    pub residual: f64,
    /// The geometric tail factors r/(1 − r) added, red, green and blue (r each channel's
    /// ratio of its last two bounces), if any.
    pub extrapolated: Option<[f64; 3]>,
    /// Seconds per bounce (the first records the transport).
    pub seconds: Vec<f64>,
    /// Seconds after the last bounce: what the receivers gathered over all of them turned
    /// into outgoing radiance, blended, added to the total, and the tree coded again.
    pub final_seconds: f64,
    /// What the recorded transport held.
    pub transport: TransportReport,
}

/// The recorded transport's size (see [`super::transport`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TransportReport {
    /// Bytes of the links kept in memory.
    pub bytes: u64,
    /// Bytes the links of every receiver take (what an unbounded budget keeps).
    pub bytes_unbounded: u64,
    /// Receiver groups kept, and gathered again in every bounce.
    pub kept_groups: usize,
    /// See `kept_groups`.
    pub regathered_groups: usize,
    /// Surfels that gather (the others blend their light, see [`super::receivers`]).
    pub receivers: usize,
    /// Slots the receivers read, of all the tree's.
    pub read_slots: usize,
    /// See `read_slots`.
    pub slots: u64,
    /// Bytes of the directional receivers' incident light summed over the bounces, and of
    /// one bounce's beside it: taken from the budget before the links.
    pub incident_bytes: u64,
}

impl BounceReport {
    /// What the cache records (no times: the cache is byte-identical from run to run).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "bounces": self.bounces,
            "energies": self.energies,
            "residual": self.residual,
            "extrapolated_tail": self.extrapolated,
        })
    }
}
