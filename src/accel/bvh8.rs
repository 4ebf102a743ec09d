//! An eight-wide bounding volume hierarchy traversed one ray at a time with SIMD (SSE2 on
//! x86-64, NEON on AArch64, through glam's `Vec4`; the node test eight boxes wide with AVX
//! where the CPU has it, checked at run time), with its triangles stored four to a packet.
//! Any-hit queries of up to eight rays that share their way (a hit's shadow rays towards one
//! light) may go together ([`Bvh8::traverse_set`]), each node visited once for all of them.
//!
//! The tree is obvhs's binary PLOC build, collapsed: each node takes its binary children and
//! keeps opening the largest (by surface area) inner one until it has eight, as Embree's BVH8
//! does. Eight-wide nodes make the tree about two thirds as deep as four-wide ones: a ray
//! visits fewer nodes, and each visit's branches (which children it entered, in which order)
//! are what a traversal spends its time on. A node stores its children's boxes as
//! structure-of-arrays (`lo[axis]` holds the eight minima, as two `Vec4`), so one ray meets
//! all eight boxes in six AVX subtractions and multiplies, or twelve SSE ones; both give the
//! same distances bit for bit (the same operations lane by lane, tested). LLVM does not merge
//! the two SSE halves into AVX by itself, hence the AVX test written out. The leaves hold at
//! most four triangles, laid out as one [`Packet`] (vertex, axis, lane), so the triangle test
//! runs on all four at once too. What each step gained, and what was tried and not kept
//! (sixteen-wide nodes, leaves of eight triangles), is in docs/benchmarks.md.
//!
//! The box test is pbrt-v4's conservative slab test (§6.1.2 and §6.8.2 of the 4th edition):
//! the far distance is scaled up by 1 + 2γ₃ so rounding never culls a box the ray touches. A
//! direction component that is exactly zero has an infinite inverse, and a ray starting
//! exactly on such a slab's plane gives 0 × ∞ = NaN there: the test ignores a NaN slab
//! distance (the ray lies in the slab for all t), so an axis-aligned ray along a box's face
//! still enters it. The near plane of each axis is chosen from the sign bit of the inverse
//! direction, the same bit the distances are computed with.

use glam::{Vec3A, Vec4};
use obvhs::bvh2::Bvh2;
use std::mem::MaybeUninit;

/// Four triangles side by side: `v[vertex][axis]` holds that coordinate of each lane's vertex;
/// `mesh` and `triangle` say which scene triangle each lane is, so that a hit needs nothing
/// else (no look-up in a table, no vertex fetched again: three cache lines, aligned, hold
/// it all); `lanes` says how many are used.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Packet {
    pub v: [[Vec4; 3]; 3],
    pub mesh: [u32; 4],
    pub triangle: [u32; 4],
    pub lanes: u32,
}

const _: () = assert!(std::mem::size_of::<Packet>() == 192);

impl Packet {
    /// The triangle in lane `lane`.
    #[inline]
    pub fn triangle(&self, lane: usize) -> [Vec3A; 3] {
        // Through arrays: glam's `Vec4` indexing is a `match`, a jump table. Written out:
        // `array::map` here was left a call, its result stored a float at a time and read
        // back whole (a stalled store forwarding per vertex).
        let corner = |c: &[Vec4; 3]| {
            Vec3A::new(
                c[0].as_ref()[lane],
                c[1].as_ref()[lane],
                c[2].as_ref()[lane],
            )
        };
        [corner(&self.v[0]), corner(&self.v[1]), corner(&self.v[2])]
    }

    /// Bit `i` set for each used lane.
    #[inline]
    pub fn used(&self) -> u32 {
        (1 << self.lanes) - 1
    }
}

/// An inner node: the boxes of up to eight children and what each child is ([`Child`]).
/// An unused slot has an empty box (min +∞, max −∞), which no ray enters.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Node {
    lo: [[Vec4; 2]; 3],
    hi: [[Vec4; 2]; 3],
    child: [u64; WIDTH],
}

/// Children per node.
const WIDTH: usize = 8;

/// A child reference: an inner node's index, or (top bit set) a leaf: its first packet in the
/// low 32 bits and its packet count above them. 64 bits wide, so no scene outgrows it.
struct Child;

impl Child {
    const LEAF: u64 = 1 << 63;
    /// An unused slot: a leaf of no packets. Its box is empty, so no ray enters it; one that
    /// did (a NaN in its box test) would visit nothing, so the traversal need not check.
    const EMPTY: u64 = Self::LEAF;

    fn leaf(first: usize, packets: usize) -> u64 {
        Self::LEAF | ((packets as u64) << 32) | first as u64
    }

    /// A leaf's packet range.
    fn packets(reference: u64) -> std::ops::Range<usize> {
        let first = (reference & 0xffff_ffff) as usize;
        let count = ((reference & !Self::LEAF) >> 32) as usize;
        first..first + count
    }
}

/// What a leaf visit tells the traversal: the (possibly shrunk) far bound for the boxes still to
/// visit, or that the query is over.
pub(crate) enum Visit {
    Bound(f32),
    Stop,
}

/// One query's ray, prepared for the box test.
#[derive(Clone, Copy)]
pub(crate) struct BoxRay {
    origin: Vec3A,
    inv: Vec3A,
    tmin: f32,
}

/// Per axis, whether a ray runs towards −axis: which of a box's planes it meets first.
type Octant = [bool; 3];

impl BoxRay {
    pub fn new(origin: Vec3A, dir: Vec3A, tmin: f32) -> BoxRay {
        BoxRay {
            origin,
            inv: Vec3A::ONE / dir,
            tmin,
        }
    }

    /// The ray's [`Octant`]: the sign bits of `inv`. Read by each traversal as it starts,
    /// from the one vector, not kept beside it: three flags stored a byte at a time by the
    /// query's set-up and loaded as one word by the traversal made the load wait for the
    /// stores to retire (a failed store-to-load forwarding: about 3 % of a path tracer's
    /// profile, 6 % of the closest-hit traversal's samples and 11 % of the occlusion one's).
    #[inline(always)]
    fn octant(&self) -> Octant {
        let bits = self.inv.is_negative_bitmask();
        [bits & 1 != 0, bits & 2 != 0, bits & 4 != 0]
    }
}

/// Whether this CPU has AVX (checked once per tree; the checks are cached by std).
fn avx_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// 1 + 2γ₃ (pbrt-v4's bound on the rounding of a slab distance).
const FAR_SCALE: f32 = 1.0 + 2.0 * crate::geometry::offset::gamma(3);

/// The larger of `t` and `acc`, keeping `acc` where `t` is NaN (`acc` never is).
#[inline(always)]
fn max_keep(t: Vec4, acc: Vec4) -> Vec4 {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        // maxps returns its second operand when either is NaN.
        t.max(acc)
    }
    #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
    {
        Vec4::select(t.cmpgt(acc), t, acc)
    }
}

/// The smaller of `t` and `acc`, keeping `acc` where `t` is NaN.
#[inline(always)]
fn min_keep(t: Vec4, acc: Vec4) -> Vec4 {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        t.min(acc)
    }
    #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
    {
        Vec4::select(t.cmplt(acc), t, acc)
    }
}

impl Node {
    const EMPTY: Node = Node {
        lo: [[Vec4::INFINITY; 2]; 3],
        hi: [[Vec4::NEG_INFINITY; 2]; 3],
        child: [Child::EMPTY; WIDTH],
    };

    /// The entry distance of the ray into each child box, and the mask of the children it
    /// enters before `tmax`.
    #[inline(always)]
    fn enter(&self, ray: &BoxRay, octant: Octant, tmax: f32) -> ([f32; WIDTH], u32) {
        let mut out = [0.0; WIDTH];
        let mut mask = 0;
        for half in 0..2 {
            let mut near = Vec4::splat(ray.tmin);
            let mut far = Vec4::splat(tmax);
            for (axis, &negative) in octant.iter().enumerate() {
                let (n, f) = if negative {
                    (self.hi[axis][half], self.lo[axis][half])
                } else {
                    (self.lo[axis][half], self.hi[axis][half])
                };
                let o = Vec4::splat(ray.origin[axis]);
                let inv = Vec4::splat(ray.inv[axis]);
                near = max_keep((n - o) * inv, near);
                far = min_keep((f - o) * inv * FAR_SCALE, far);
            }
            out[4 * half..4 * half + 4].copy_from_slice(&near.to_array());
            mask |= near.cmple(far).bitmask() << (4 * half);
        }
        (out, mask)
    }

    /// [`Node::enter`] with AVX: all eight boxes in one register per step, the same
    /// operations in the same order lane by lane (`vmaxps` and `vminps` return their second
    /// operand where either is NaN, as `max_keep` and `min_keep` do).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    fn enter_avx(&self, ray: &BoxRay, octant: Octant, tmax: f32) -> ([f32; WIDTH], u32) {
        use std::arch::x86_64::*;
        let mut near = _mm256_set1_ps(ray.tmin);
        let mut far = _mm256_set1_ps(tmax);
        let scale = _mm256_set1_ps(FAR_SCALE);
        for (axis, &negative) in octant.iter().enumerate() {
            let (n, f) = if negative {
                (&self.hi[axis], &self.lo[axis])
            } else {
                (&self.lo[axis], &self.hi[axis])
            };
            // SAFETY: `[Vec4; 2]` is eight contiguous f32 (glam's `Vec4` is four f32 in 16
            // bytes, no padding), read unaligned.
            let (n, f) = unsafe {
                (
                    _mm256_loadu_ps(n.as_ptr().cast::<f32>()),
                    _mm256_loadu_ps(f.as_ptr().cast::<f32>()),
                )
            };
            let o = _mm256_set1_ps(ray.origin[axis]);
            let inv = _mm256_set1_ps(ray.inv[axis]);
            near = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(n, o), inv), near);
            far = _mm256_min_ps(
                _mm256_mul_ps(_mm256_mul_ps(_mm256_sub_ps(f, o), inv), scale),
                far,
            );
        }
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(near, far)) as u32;
        let mut out = [0.0; WIDTH];
        // SAFETY: `out` holds eight f32.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), near) };
        (out, mask)
    }
}

/// The tree: inner nodes, leaf packets and the root reference.
pub(crate) struct Bvh8 {
    nodes: Vec<Node>,
    pub packets: Vec<Packet>,
    root: u64,
    /// Whether the node test runs eight boxes wide with AVX (the CPU has it).
    avx: bool,
    /// Stack entries a traversal can need: seven per level below the root, plus one (a node
    /// that a ray enters three or more children of writes all eight before it takes the
    /// nearest back).
    stack_size: usize,
}

/// A binary node still to collapse: where its reference goes (`None` for the root, else the
/// eight-wide node and slot) and its depth in the eight-wide tree.
struct Pending {
    node: usize,
    slot: Option<(usize, usize)>,
    level: usize,
}

/// A traversal stack entry: a child reference and the distance at which the ray enters it.
type Entry = (u64, f32);

/// A set traversal's stack entry: a child reference and the rays that entered it.
type SetEntry = (u64, u32);

/// The most rays [`Bvh8::traverse_set`] takes at once (one byte of a 64-bit mask per ray).
pub(crate) const SET: usize = 8;

/// The transpose of the 8 × 8 bit matrix whose row `i` is byte `i` of `x` (bit `k` of the
/// byte its column `k`): byte `k` of the result holds bit `k` of every row. Three swaps of
/// ever larger blocks (Hacker's Delight, §7-3).
#[inline(always)]
fn transpose_bits(mut x: u64) -> u64 {
    let t = (x ^ (x >> 7)) & 0x00aa_00aa_00aa_00aa;
    x ^= t ^ (t << 7);
    let t = (x ^ (x >> 14)) & 0x0000_cccc_0000_cccc;
    x ^= t ^ (t << 14);
    let t = (x ^ (x >> 28)) & 0x0000_0000_f0f0_f0f0;
    x ^ t ^ (t << 28)
}

/// Traversals whose stack fits this many entries keep it on the call stack.
const INLINE_STACK: usize = 192;

impl Bvh8 {
    /// Collapse obvhs's binary tree over `triangles` (`[v0, v1, v2]` each, `ids[i]` the
    /// mesh and triangle of `triangles[i]`) into eight-wide nodes and packets.
    pub(crate) fn from_bvh2(bvh2: &Bvh2, triangles: &[[Vec3A; 3]], ids: &[(u32, u32)]) -> Bvh8 {
        let mut out = Bvh8 {
            nodes: Vec::new(),
            packets: Vec::new(),
            root: Child::EMPTY,
            avx: avx_available(),
            stack_size: 1,
        };
        if bvh2.nodes.is_empty() || triangles.is_empty() {
            return out;
        }
        let mut work = vec![Pending {
            node: 0,
            slot: None,
            level: 0,
        }];
        let mut depth = 0;
        while let Some(Pending {
            node: n,
            slot,
            level,
        }) = work.pop()
        {
            depth = depth.max(level);
            let node = &bvh2.nodes[n];
            let reference = if node.prim_count > 0 {
                let first = node.first_index as usize;
                out.leaf(
                    &bvh2.primitive_indices[first..first + node.prim_count as usize],
                    triangles,
                    ids,
                )
            } else {
                let index = out.nodes.len();
                out.nodes.push(Node::EMPTY);
                for (k, c) in Self::open(bvh2, n).into_iter().enumerate() {
                    let b = &bvh2.nodes[c].aabb;
                    let node = &mut out.nodes[index];
                    for axis in 0..3 {
                        node.lo[axis][k / 4][k % 4] = b.min[axis];
                        node.hi[axis][k / 4][k % 4] = b.max[axis];
                    }
                    work.push(Pending {
                        node: c,
                        slot: Some((index, k)),
                        level: level + 1,
                    });
                }
                index as u64
            };
            match slot {
                None => out.root = reference,
                Some((parent, k)) => out.nodes[parent].child[k] = reference,
            }
        }
        out.stack_size = (WIDTH - 1) * depth + 1;
        out
    }

    /// Up to eight binary-tree nodes below inner node `n`: its two children, then, while there
    /// is room, the largest inner one replaced by its own two children.
    fn open(bvh2: &Bvh2, n: usize) -> Vec<usize> {
        let first = bvh2.nodes[n].first_index as usize;
        let mut children = vec![first, first + 1];
        while children.len() < WIDTH {
            let largest = children
                .iter()
                .enumerate()
                .filter(|(_, &c)| bvh2.nodes[c].prim_count == 0)
                .max_by(|a, b| {
                    let area = |c: usize| bvh2.nodes[c].aabb.half_area();
                    area(*a.1).total_cmp(&area(*b.1))
                });
            let Some((k, &c)) = largest else { break };
            let first = bvh2.nodes[c].first_index as usize;
            children[k] = first;
            children.insert(k + 1, first + 1);
        }
        children
    }

    /// Lay out the triangles `members` (indices into `triangles` and `ids`) as packets and
    /// return the leaf's reference.
    fn leaf(&mut self, members: &[u32], triangles: &[[Vec3A; 3]], ids: &[(u32, u32)]) -> u64 {
        let first = self.packets.len();
        for chunk in members.chunks(4) {
            let mut p = Packet {
                v: [[Vec4::ZERO; 3]; 3],
                mesh: [0; 4],
                triangle: [0; 4],
                lanes: chunk.len() as u32,
            };
            for lane in 0..4 {
                // Unused lanes repeat the first triangle (masked out by `used`).
                let i = chunk.get(lane).copied().unwrap_or(chunk[0]) as usize;
                let t = triangles[i];
                (p.mesh[lane], p.triangle[lane]) = ids[i];
                for (vertex, v) in t.iter().enumerate() {
                    for axis in 0..3 {
                        p.v[vertex][axis][lane] = v[axis];
                    }
                }
            }
            self.packets.push(p);
        }
        Child::leaf(first, self.packets.len() - first)
    }

    /// Visit the leaves the ray `(ray, tmin…tmax)` enters, nearest box first when `ordered`.
    /// `visit` sees a leaf's packets and returns the new far bound (a closest-hit query
    /// shrinks it) or [`Visit::Stop`]. Returns false when a visit stopped the query.
    #[inline]
    pub fn traverse<'s>(
        &'s self,
        ray: &BoxRay,
        tmax: f32,
        ordered: bool,
        visit: impl FnMut(&'s [Packet]) -> Visit,
    ) -> bool {
        if self.root == Child::EMPTY {
            return true;
        }
        // One call of `traverse_with`, so that `visit` is inlined into it (the closures
        // `#[inline(always)]`: see the module docs of `accel`).
        self.with_stack(
            #[inline(always)]
            |stack: &mut [MaybeUninit<Entry>]| {
                #[cfg(target_arch = "x86_64")]
                if self.avx {
                    // SAFETY: `avx` is set only where the CPU has AVX.
                    return unsafe { self.traverse_avx(stack, ray, tmax, ordered, visit) };
                }
                self.traverse_with::<false>(stack, ray, tmax, ordered, visit)
            },
        )
    }

    /// Run `f` with a traversal stack of `stack_size` entries: on the call stack where it
    /// fits [`INLINE_STACK`], else on the heap. Uninitialised: zeroing 3 KiB per ray cost as
    /// much as a third of a traversal.
    #[inline(always)]
    fn with_stack<E: Copy, R>(&self, f: impl FnOnce(&mut [MaybeUninit<E>]) -> R) -> R {
        if self.stack_size <= INLINE_STACK {
            let mut inline = [const { MaybeUninit::uninit() }; INLINE_STACK];
            f(&mut inline)
        } else {
            f(&mut vec![MaybeUninit::uninit(); self.stack_size])
        }
    }

    /// Visit the leaves that each ray `i` of `rays` in the mask `open` enters before
    /// `tmax[i]`, every leaf once for all the rays still open that entered it, in no particular
    /// order: an any-hit query for rays that share most of their way through the tree
    /// (shadow rays from one point towards one light). `visit` sees a leaf's packets and the
    /// mask of the open rays that reached it, and returns the rays it finished (found
    /// occluded); they take no further part. Returns the mask of finished rays.
    ///
    /// Each ray reaches exactly the leaves its own [`Bvh8::traverse`] would (with a far bound
    /// that does not shrink): a child is entered for the rays whose own node test enters it,
    /// so an any-hit answer per ray is the one-ray query's.
    pub fn traverse_set(
        &self,
        rays: &[BoxRay; SET],
        tmax: &[f32; SET],
        open: u32,
        visit: impl FnMut(&[Packet], u32) -> u32,
    ) -> u32 {
        if self.root == Child::EMPTY || open == 0 {
            return 0;
        }
        self.with_stack(
            #[inline(always)]
            |stack: &mut [MaybeUninit<SetEntry>]| {
                #[cfg(target_arch = "x86_64")]
                if self.avx {
                    // SAFETY: `avx` is set only where the CPU has AVX.
                    return unsafe { self.traverse_set_avx(stack, (rays, tmax, open), visit) };
                }
                self.traverse_set_with::<false>(stack, (rays, tmax, open), visit)
            },
        )
    }

    /// [`Bvh8::traverse_set_with`] compiled with AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn traverse_set_avx(
        &self,
        stack: &mut [MaybeUninit<SetEntry>],
        set: (&[BoxRay; SET], &[f32; SET], u32),
        visit: impl FnMut(&[Packet], u32) -> u32,
    ) -> u32 {
        self.traverse_set_with::<true>(stack, set, visit)
    }

    #[inline(always)]
    fn traverse_set_with<const AVX: bool>(
        &self,
        stack: &mut [MaybeUninit<SetEntry>],
        (rays, tmax, all): (&[BoxRay; SET], &[f32; SET], u32),
        mut visit: impl FnMut(&[Packet], u32) -> u32,
    ) -> u32 {
        let mut done = 0u32;
        let mut top = 0;
        let (mut current, mut open) = (self.root, all);
        loop {
            if current & Child::LEAF == 0 {
                let node = &self.nodes[current as usize];
                // Row i (byte i): the children ray i enters; transposed, byte k is the rays
                // that enter child k.
                let mut rows = 0u64;
                let mut left = open;
                while left != 0 {
                    let i = left.trailing_zeros() as usize;
                    left &= left - 1;
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: `AVX` is true only inside `traverse_set_avx`, compiled with AVX.
                    let (_, mask) = if AVX {
                        unsafe { node.enter_avx(&rays[i], rays[i].octant(), tmax[i]) }
                    } else {
                        node.enter(&rays[i], rays[i].octant(), tmax[i])
                    };
                    #[cfg(not(target_arch = "x86_64"))]
                    let (_, mask) = node.enter(&rays[i], rays[i].octant(), tmax[i]);
                    rows |= u64::from(mask) << (8 * i);
                }
                let columns = transpose_bits(rows);
                let mut next = None;
                for (k, &child) in node.child.iter().enumerate() {
                    let entered = ((columns >> (8 * k)) & 0xff) as u32;
                    if entered == 0 || child == Child::EMPTY {
                        continue;
                    }
                    if let Some(previous) = next.replace((child, entered)) {
                        stack[top].write(previous);
                        top += 1;
                    }
                }
                if let Some((child, entered)) = next {
                    (current, open) = (child, entered);
                    continue;
                }
            } else {
                done |= visit(&self.packets[Child::packets(current)], open) & open;
                if done == all {
                    return done;
                }
            }
            // The next entry some of whose rays are still open.
            loop {
                if top == 0 {
                    return done;
                }
                top -= 1;
                // SAFETY: every entry below `top` was written before `top` passed it, and
                // a node pushes at most seven, as in `traverse_with`.
                let (child, entered) = unsafe { stack[top].assume_init() };
                if entered & !done != 0 {
                    (current, open) = (child, entered & !done);
                    break;
                }
            }
        }
    }

    /// Test the nodes with AVX where `on` and the CPU has it, else with SSE.
    #[cfg(test)]
    pub(crate) fn use_avx(&mut self, on: bool) {
        self.avx = on && avx_available();
    }

    /// [`Bvh8::traverse_with`] compiled with AVX, its node test eight boxes wide.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn traverse_avx<'s>(
        &'s self,
        stack: &mut [MaybeUninit<Entry>],
        ray: &BoxRay,
        tmax: f32,
        ordered: bool,
        visit: impl FnMut(&'s [Packet]) -> Visit,
    ) -> bool {
        self.traverse_with::<true>(stack, ray, tmax, ordered, visit)
    }

    #[inline(always)]
    fn traverse_with<'s, const AVX: bool>(
        &'s self,
        stack: &mut [MaybeUninit<Entry>],
        ray: &BoxRay,
        mut tmax: f32,
        ordered: bool,
        mut visit: impl FnMut(&'s [Packet]) -> Visit,
    ) -> bool {
        let mut top = 0;
        let mut current = self.root;
        let octant = ray.octant();
        loop {
            if current & Child::LEAF == 0 {
                let node = &self.nodes[current as usize];
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `AVX` is true only inside `traverse_avx`, compiled with AVX.
                let (near, mut mask) = if AVX {
                    unsafe { node.enter_avx(ray, octant, tmax) }
                } else {
                    node.enter(ray, octant, tmax)
                };
                #[cfg(not(target_arch = "x86_64"))]
                let (near, mut mask) = node.enter(ray, octant, tmax);
                // The entered children, pushed farthest first so the nearest is visited next;
                // equally near ones in slot order, the last visited first.
                if mask != 0 {
                    let first = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        // One child (most visits): no sorting, nothing pushed.
                        current = node.child[first];
                        continue;
                    }
                    let second = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let a = (node.child[first], near[first]);
                    let b = (node.child[second], near[second]);
                    if mask == 0 {
                        // Two: the farther pushed (the later slot where they tie).
                        let (far, next) = if ordered && a.1 < b.1 { (b, a) } else { (a, b) };
                        stack[top].write(far);
                        top += 1;
                        current = next.0;
                        continue;
                    }
                    // Three or more: an insertion sort, farthest first, on the stack itself.
                    let base = top;
                    for entry in [a, b] {
                        stack[top].write(entry);
                        top += 1;
                    }
                    while mask != 0 {
                        let k = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        stack[top].write((node.child[k], near[k]));
                        top += 1;
                    }
                    if ordered {
                        for i in base + 1..top {
                            let mut j = i;
                            // SAFETY: entries `base..top` were written just above.
                            while j > base
                                && unsafe {
                                    stack[j - 1].assume_init().1 < stack[j].assume_init().1
                                }
                            {
                                stack.swap(j - 1, j);
                                j -= 1;
                            }
                        }
                    }
                    top -= 1;
                    // SAFETY: written above.
                    current = unsafe { stack[top].assume_init() }.0;
                    continue;
                }
            } else {
                match visit(&self.packets[Child::packets(current)]) {
                    Visit::Bound(t) => tmax = t,
                    Visit::Stop => return false,
                }
            }
            // The next entry the ray still enters before the (possibly shrunk) bound.
            loop {
                if top == 0 {
                    return true;
                }
                top -= 1;
                // SAFETY: every entry below `top` was written by the push above before `top`
                // passed it, and `stack` holds `stack_size` entries, the most a tree of this
                // depth can push (seven per level, and the eighth a node writes for a moment).
                let (child, near) = unsafe { stack[top].assume_init() };
                if near <= tmax {
                    current = child;
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Sampler;

    /// The bit transpose moves bit k of byte i to bit i of byte k, for every one of the 64
    /// positions alone and for random words (against the definition, bit by bit).
    #[test]
    fn transpose_bits_moves_each_bit_across_the_diagonal() {
        let naive = |x: u64| {
            let mut out = 0u64;
            for i in 0..8 {
                for k in 0..8 {
                    out |= ((x >> (8 * i + k)) & 1) << (8 * k + i);
                }
            }
            out
        };
        for b in 0..64 {
            assert_eq!(transpose_bits(1 << b), naive(1 << b), "bit {b}");
        }
        let mut s = Sampler::new(5, 0, 0);
        for _ in 0..1000 {
            let x = (u64::from(s.next_u32()) << 32) | u64::from(s.next_u32());
            assert_eq!(transpose_bits(x), naive(x));
        }
    }

    /// The AVX node test gives the SSE one's entry distances and mask bit for bit: random
    /// boxes (some empty, some flat) against random rays, rays along the axes (a zero
    /// direction component, an infinite inverse) and rays starting on a box's face plane
    /// (0 × ∞ = NaN in the slab test).
    #[test]
    fn avx_node_test_matches_sse() {
        // Without AVX there is nothing to compare: the traversal never takes that path.
        if !avx_available() {
            return;
        }
        let mut s = Sampler::new(11, 0, 0);
        let mut value = |grid: bool| {
            let v = s.next_1d() * 8.0 - 4.0;
            if grid {
                v.round()
            } else {
                v
            }
        };
        let mut entered = 0;
        for round in 0..20_000 {
            let grid = round % 2 == 0;
            let mut node = Node::EMPTY;
            for k in 0..WIDTH - round % 3 {
                for axis in 0..3 {
                    let (a, b) = (value(grid), value(grid));
                    node.lo[axis][k / 4][k % 4] = a.min(b);
                    node.hi[axis][k / 4][k % 4] = a.max(b);
                }
            }
            let origin = Vec3A::new(value(grid), value(grid), value(grid));
            let mut dir = Vec3A::new(value(grid), value(grid), value(grid));
            if round % 5 == 0 {
                dir[round % 3] = if round % 10 == 0 { 0.0 } else { -0.0 };
            }
            if dir == Vec3A::ZERO {
                dir = Vec3A::X;
            }
            let ray = BoxRay::new(origin, dir.normalize(), 0.0);
            let tmax = if round % 4 == 0 { 3.0 } else { f32::INFINITY };
            let (near, mask) = node.enter(&ray, ray.octant(), tmax);
            // SAFETY: AVX is available (checked above).
            let (near_avx, mask_avx) = unsafe { node.enter_avx(&ray, ray.octant(), tmax) };
            assert_eq!(mask, mask_avx, "round {round}");
            assert_eq!(
                near.map(f32::to_bits),
                near_avx.map(f32::to_bits),
                "round {round}"
            );
            entered += mask.count_ones();
        }
        assert!(
            entered > 10_000,
            "{entered} boxes entered: the test must exercise hits"
        );
    }
}
