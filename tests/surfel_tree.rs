//! The surfel tree and its hierarchical wavelet coding (docs/method.md §6, docs/design.md §5.5–§5.6).

use glam::{Vec2, Vec3};
use wpbgi::haar::{texel_directions, Haar2d, SparseHaar};
use wpbgi::sampler::Sampler;
use wpbgi::spectrum::Rgb;
use wpbgi::surfels::coding::encode;
use wpbgi::surfels::tree::SurfelTree;
use wpbgi::surfels::Surfel;

/// Surfels on a wavy patch plus a few on a second, facing patch: normals vary.
fn surfels(n: usize) -> Vec<Surfel> {
    (0..n)
        .map(|i| {
            let mut s = Sampler::new(1, i as u64, 0);
            let (x, y) = (s.next_1d() * 4.0, s.next_1d() * 4.0);
            let flip = i % 7 == 0;
            let p = Vec3::new(x, y, 0.3 * (x * 1.7).sin() + if flip { 2.0 } else { 0.0 });
            let n = Vec3::new(-0.51 * (x * 1.7).cos(), 0.0, 1.0).normalize();
            Surfel {
                p,
                n: if flip { -n } else { n },
                area: 0.01 * (1.0 + s.next_1d()),
                mesh: 0,
                triangle: 0,
                b: Vec2::ZERO,
            }
        })
        .collect()
}

const N: usize = 8;
/// The maps' levels (log2 of N).
const LEVELS: u32 = N.trailing_zeros();

/// A surfel's radiant-intensity map: A max(0, n·ω) L(ω) with a glossy-ish L that differs per
/// surfel.
fn texels(s: &Surfel, i: u32) -> Vec<Rgb> {
    let lobe = Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.91).cos(), 1.0).normalize();
    texel_directions(N.trailing_zeros())
        .iter()
        .map(|&w| {
            let l =
                Rgb::new(0.5, 0.4, 0.3) + Rgb::new(2.0, 1.5, 1.0) * w.dot(lobe).max(0.0).powi(8);
            l * (s.area * s.n.dot(w).max(0.0))
        })
        .collect()
}

fn leaf_maps(s: &[Surfel]) -> Vec<Haar2d<Rgb>> {
    s.iter()
        .enumerate()
        .map(|(i, x)| Haar2d::forward(&texels(x, i as u32), N))
        .collect()
}

/// A map with every non-zero coefficient: what `encode` takes per leaf.
fn exact(m: &Haar2d<Rgb>) -> SparseHaar<Rgb> {
    SparseHaar::compress_below(m, 0.0)
}

/// The coding as docs/method.md §6 writes it, on dense maps: per node the exact G = G(left) + G(right)
/// and H = (G(left) − G(right))/2, each kept above τ‖G‖ ([`Haar2d::combine`], [`Haar2d::norm`]).
fn dense_coding(
    tree: &SurfelTree,
    maps: &[Haar2d<Rgb>],
    eps: u32,
    tau: f32,
) -> Vec<[Option<SparseHaar<Rgb>>; 2]> {
    let mut g: Vec<Option<Haar2d<Rgb>>> = vec![None; tree.nodes.len()];
    let mut stored = vec![[None, None]; tree.nodes.len()];
    // Children follow their parents (breadth-first), so a reverse sweep is post-order enough.
    for j in (0..tree.nodes.len()).rev() {
        let n = &tree.nodes[j];
        let (gj, h) = if n.is_leaf() {
            (maps[tree.order[n.first as usize] as usize].clone(), None)
        } else {
            let [l, r] = n
                .children
                .map(|c| g[c as usize].as_ref().expect("child first"));
            (
                Haar2d::combine(l, 1.0, r, 1.0),
                Some(Haar2d::combine(l, 0.5, r, -0.5)),
            )
        };
        let cut = tau * gj.norm();
        let keep = |m: &Haar2d<Rgb>| SparseHaar::compress_below(m, cut).refined_to(LEVELS);
        stored[j] = [
            (n.level <= eps).then(|| keep(&gj)),
            h.filter(|_| n.level >= eps).map(|h| keep(&h)),
        ];
        g[j] = Some(gj);
    }
    stored
}

/// The sparse coder stores what the dense one does, coefficient for coefficient.
#[test]
fn sparse_coding_is_the_dense_coding_bit_for_bit() {
    let s = surfels(400);
    let tree = SurfelTree::build(&s);
    // Leaves with every coefficient, and sparse ones (thresholded as light maps are).
    let full = leaf_maps(&s);
    let sparse: Vec<Haar2d<Rgb>> = full
        .iter()
        .map(|m| SparseHaar::compress(m, 0.05).to_dense())
        .collect();
    for (maps, eps, tau) in [
        (&full, 0, 0.0),
        (&full, 3, 2e-3),
        (&sparse, 3, 2e-3),
        (&sparse, 3, 5e-2),
        (&sparse, tree.depth(), 1e-2),
    ] {
        let coded = encode(&tree, &|i| exact(&maps[i as usize]), LEVELS, eps, tau);
        let dense = dense_coding(&tree, maps, eps, tau);
        for (j, (ours, theirs)) in coded.nodes.iter().zip(&dense).enumerate() {
            assert_eq!(ours.g, theirs[0], "eps {eps}, tau {tau}, node {j}: G");
            assert_eq!(ours.h, theirs[1], "eps {eps}, tau {tau}, node {j}: H");
        }
    }
}

/// The exact aggregate of node `j`: the sum of its surfels' maps.
fn aggregate(tree: &SurfelTree, maps: &[Haar2d<Rgb>], j: usize) -> Haar2d<Rgb> {
    let n = &tree.nodes[j];
    let ids = &tree.order[n.first as usize..(n.first + n.count) as usize];
    let mut g = maps[ids[0] as usize].clone();
    for &i in &ids[1..] {
        g = Haar2d::combine(&g, 1.0, &maps[i as usize], 1.0);
    }
    g
}

fn distance(a: &Haar2d<Rgb>, b: &Haar2d<Rgb>) -> f32 {
    Haar2d::combine(a, 1.0, b, -1.0).norm()
}

#[test]
fn tree_is_balanced_and_bounds_are_conservative() {
    let s = surfels(1000);
    let tree = SurfelTree::build(&s);
    assert_eq!(tree.nodes.len(), 2 * s.len() - 1);
    assert_eq!(tree.depth(), 11, "⌈log2 1000⌉ + 1 levels");
    let mut sorted = tree.order.clone();
    sorted.sort_unstable();
    assert!(
        sorted.iter().enumerate().all(|(i, &x)| i as u32 == x),
        "a permutation"
    );
    for (j, n) in tree.nodes.iter().enumerate() {
        if j > 0 {
            assert!(
                n.level >= tree.nodes[j - 1].level,
                "breadth-first, coarse to fine"
            );
        }
        let ids = &tree.order[n.first as usize..(n.first + n.count) as usize];
        let area: f32 = ids.iter().map(|&i| s[i as usize].area).sum();
        assert!((n.area - area).abs() <= 1e-5 * area);
        for &i in ids {
            let x = &s[i as usize];
            assert!(
                x.p.distance(n.center) + x.radius() <= n.radius * (1.0 + 1e-5),
                "sphere"
            );
            let angle = x.n.cross(n.axis).length().atan2(x.n.dot(n.axis));
            assert!(
                angle <= n.cone_angle + 1e-6,
                "normal cone of node {j}: {angle} > {}",
                n.cone_angle
            );
        }
    }
}

#[test]
fn lossless_coding_reconstructs_every_node_exactly() {
    let s = surfels(300);
    let tree = SurfelTree::build(&s);
    let maps = leaf_maps(&s);
    for eps in [0, 3, tree.depth()] {
        let coded = encode(&tree, &|i| exact(&maps[i as usize]), LEVELS, eps, 0.0);
        for j in 0..tree.nodes.len() {
            let exact = aggregate(&tree, &maps, j);
            let ours = coded.reconstruct(&tree, j as u32).expect("reconstructs");
            assert!(
                distance(&ours, &exact) <= 1e-5 * exact.norm(),
                "eps {eps}, node {j}: off by {}",
                distance(&ours, &exact)
            );
        }
    }
}

/// With a threshold, each node's error is bounded by what was dropped on its path: the anchor's
/// G contributes 2^−(l−ε) τ‖G(a)‖ √(dropped), each H(k) 2^−(l−lₖ−1) τ‖G(k)‖ √(dropped).
#[test]
fn thresholded_coding_error_is_bounded() {
    let s = surfels(300);
    let tree = SurfelTree::build(&s);
    let maps = leaf_maps(&s);
    let (eps, tau) = (3u32, 2e-3f32);
    let coded = encode(&tree, &|i| exact(&maps[i as usize]), LEVELS, eps, tau);
    let total = 1 + 3 * maps[0].details.len();
    let dropped = |m: &Option<SparseHaar<Rgb>>| {
        (total - m.as_ref().expect("stored").coefficient_count()) as f32
    };
    let mut worst: f32 = 0.0;
    for j in 0..tree.nodes.len() {
        let exact = aggregate(&tree, &maps, j);
        let ours = coded.reconstruct(&tree, j as u32).expect("reconstructs");
        // Walk up to the anchor, accumulating the bound.
        let level = tree.nodes[j].level;
        let mut bound = 0.0;
        let mut at = j;
        while coded.nodes[at].g.is_none() {
            let k = tree.nodes[at].parent as usize;
            let lk = tree.nodes[k].level;
            bound += 0.5f32.powi((level - lk - 1) as i32)
                * tau
                * aggregate(&tree, &maps, k).norm()
                * dropped(&coded.nodes[k].h).sqrt();
            at = k;
        }
        let la = tree.nodes[at].level;
        bound += 0.5f32.powi((level - la) as i32)
            * tau
            * aggregate(&tree, &maps, at).norm()
            * dropped(&coded.nodes[at].g).sqrt();
        let err = distance(&ours, &exact);
        assert!(
            err <= bound * 1.001 + 1e-6 * exact.norm(),
            "node {j}: error {err} > bound {bound}"
        );
        worst = worst.max(err / exact.norm());
        // Point evaluation walks the same path.
        let mut r = Sampler::new(2, j as u64, 0);
        let p = r.next_2d();
        let e = coded.eval(&tree, j as u32, p.x, p.y).expect("evaluates");
        assert!((e - ours.eval(p.x, p.y)).abs().max_element() <= 1e-4 * exact.norm());
    }
    let (maps_stored, kept) = coded.stored_counts();
    let dense = tree.nodes.len() * total;
    eprintln!(
        "tau {tau}, eps {eps}: {maps_stored} maps, {kept} coefficients kept of {dense} for every node's G \
         ({:.1} % of the memory), worst relative L2 error {worst:.2e}",
        100.0 * kept as f64 / dense as f64
    );
    assert!(kept < dense / 2, "hierarchical coding saves memory");
}

/// Leaves at their own, coarser resolutions (a diffuse surfel's 8² lobe in a tree of 64² maps)
/// code exactly as the same leaves refined to the tree's: the same stored coefficients, at the
/// tree's resolution.
#[test]
fn coarse_leaves_code_as_refined_ones() {
    let s = surfels(300);
    let tree = SurfelTree::build(&s);
    // Every third leaf at a coarser resolution: its texels averaged over 2 × 2 or 4 × 4 blocks.
    let coarse: Vec<Haar2d<Rgb>> = s
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let down = (i % 3) as u32;
            let fine = texels(x, i as u32);
            let side = N >> down;
            let block = 1usize << down;
            let texels: Vec<Rgb> = (0..side * side)
                .map(|t| {
                    let (cx, cy) = (t % side, t / side);
                    let mut sum = Rgb::ZERO;
                    for y in cy * block..(cy + 1) * block {
                        for x in cx * block..(cx + 1) * block {
                            sum += fine[y * N + x];
                        }
                    }
                    sum / (block * block) as f32
                })
                .collect();
            Haar2d::forward(&texels, side)
        })
        .collect();
    for (eps, tau) in [(3, 0.0), (3, 2e-3), (tree.depth(), 1e-2)] {
        let ours = encode(&tree, &|i| exact(&coarse[i as usize]), LEVELS, eps, tau);
        let refined = encode(
            &tree,
            &|i| exact(&coarse[i as usize].refined_to(LEVELS)),
            LEVELS,
            eps,
            tau,
        );
        assert_eq!(ours, refined, "eps {eps}, tau {tau}");
        assert!(ours
            .nodes
            .iter()
            .flat_map(|n| [&n.g, &n.h])
            .flatten()
            .all(|m| m.levels() == LEVELS));
    }
}

#[test]
fn coding_is_independent_of_thread_count() {
    let s = surfels(500);
    let tree = SurfelTree::build(&s);
    let maps = leaf_maps(&s);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| encode(&tree, &|i| exact(&maps[i as usize]), LEVELS, 2, 1e-3))
    };
    assert_eq!(run(1), run(2));
}
