//! How many bounces to run, how finely, and how much memory their recorded transport may
//! take: the settings the bake passes to [`super::add_bounces`].

use super::transport::Slots;
use crate::cache::store::{NodeRecord, SurfelRecord};
use crate::error::{Error, Result};
use crate::gather::senders::{NodeDetail, SenderNode};
use crate::validate::{in_range, require};

/// The default [`BounceSettings::receiver_stride`] (see docs/bounces.md for its measure).
pub(crate) const RECEIVER_STRIDE: u32 = 16;

/// How many bounces to run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BounceSettings {
    /// The most explicit bounces.
    pub max: u32,
    /// Stop when a bounce carries less than this fraction of the reflected total; 0 runs
    /// exactly `max` bounces without extrapolation.
    pub tolerance: f32,
    /// The most of its L2 norm each column of a BSDF operator may lose to thresholding.
    pub operator_tau: f32,
    /// Share the far part of the gather among nearby surfels (the view tree, see
    /// [`super::view_tree`]); otherwise every surfel traverses the whole tree.
    pub view_tree: bool,
    /// About one surfel in this many gathers in each bounce; the others blend the light of
    /// their nearest gathering neighbours on the same surface (see [`super::receivers`]).
    /// 1: every surfel gathers.
    pub receiver_stride: u32,
    /// The most bytes the recorded transport may hold, with the receivers' summed light
    /// ([`TransportReport::incident_bytes`](super::TransportReport::incident_bytes)); receivers past it gather again in every
    /// bounce. It changes the time, never the cache (so it is not part of the cache's
    /// hash). `None`: [`default_transport_budget`].
    pub transport_budget: Option<u64>,
}

/// The transport's default memory budget: 40 % of the machine's physical memory (the rest
/// holds the surfels, the tree, the cache being written and the other processes), or 4 GiB
/// where the machine does not say.
pub fn default_transport_budget() -> u64 {
    const FRACTION: f64 = 0.4;
    crate::machine::total_memory().map_or(4 << 30, |b| (b as f64 * FRACTION) as u64)
}

/// The least memory (bytes) the bounces of a bake of `points` surfels, whose tree's maps have
/// `levels`, hold besides the bake itself, with no transport kept: the tree as senders (a
/// node record, a sender node and its detail per node, a surfel record per surfel, two nodes per surfel)
/// and the bitmap of the transport's slots.
pub(crate) fn memory_floor(points: u64, levels: u32) -> u64 {
    let nodes = 2 * points;
    let senders = nodes
        * (size_of::<NodeRecord>() + size_of::<SenderNode>() + size_of::<NodeDetail>()) as u64
        + points * size_of::<SurfelRecord>() as u64;
    senders + Slots::fewest(points, levels) / 8
}

/// Refuse bounces whose transport slots cannot be numbered in 32 bits, before any work (see
/// [`Slots`]), naming the largest point count that fits.
pub(crate) fn check_slots(points: u64, levels: u32) -> Result<()> {
    let slots = Slots::fewest(points, levels);
    if slots < u64::from(u32::MAX) {
        return Ok(());
    }
    // fewest(p) = p (4 + k) − (3 + k) with k = 4^levels, below 2^32 − 1.
    let k = 1u64 << (2 * levels);
    let most = (u64::from(u32::MAX) + 2 + k) / (4 + k);
    Err(Error::InvalidSetting(format!(
        "the bounces of {points} surfels with {side} × {side} maps would read at least {slots} \
         values of the tree, more than 2^32; bake at most about {most} points (--points), or \
         rougher materials (coarser maps)",
        side = 1u32 << levels
    )))
}

impl BounceSettings {
    /// `auto`: up to 30 bounces, stopping once one adds less than 3 % of the total, with the
    /// geometric tail of the rest, channel by channel (docs/bounces.md, "Bounce control",
    /// measures the choice).
    pub const fn auto() -> Self {
        BounceSettings {
            max: 30,
            tolerance: 3e-2,
            operator_tau: 1e-2,
            view_tree: true,
            receiver_stride: RECEIVER_STRIDE,
            transport_budget: None,
        }
    }

    /// Exactly `n` bounces.
    pub const fn exactly(n: u32) -> Self {
        BounceSettings {
            max: n,
            tolerance: 0.0,
            ..Self::auto()
        }
    }

    /// No bounces: a cache of direct light only.
    pub const NONE: BounceSettings = BounceSettings::exactly(0);

    /// Refuse a field out of range, in a sentence that names it.
    pub fn validate(&self) -> Result<()> {
        const S: &str = "BounceSettings";
        require(
            in_range(self.tolerance, 0.0, 1.0, false),
            S,
            "tolerance",
            self.tolerance,
            "a number in [0, 1) (0: exactly `max` bounces)",
        )?;
        require(
            in_range(self.operator_tau, 0.0, 1.0, false),
            S,
            "operator_tau",
            self.operator_tau,
            "a number in [0, 1)",
        )?;
        require(
            self.receiver_stride >= 1,
            S,
            "receiver_stride",
            self.receiver_stride,
            "at least 1 (1: every surfel gathers)",
        )
    }
}

/// `auto` for [`BounceSettings::auto`], otherwise the count: what `wpbgi bake --bounces`
/// reads back.
impl std::fmt::Display for BounceSettings {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if *self == BounceSettings::auto() {
            f.write_str("auto")
        } else {
            write!(f, "{}", self.max)
        }
    }
}
