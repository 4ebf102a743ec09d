//! The Haar transform and the equal-area octahedral map (docs/method.md §4.2, docs/design.md §5.3).

use glam::{DVec2, Vec2, Vec3};
use wpbgi::geometry::warp::square_to_uniform_sphere;
use wpbgi::haar::sphere_map::square_to_direction_f64;
use wpbgi::haar::{
    direction_to_square, square_to_direction, texel_directions, texel_of, Haar2d, PointMap,
    SparseHaar, SparseSum,
};
use wpbgi::sampler::Sampler;

fn random_image(n: usize, seed: u64) -> Vec<Vec3> {
    (0..n * n)
        .map(|i| {
            let mut s = Sampler::new(seed, i as u64, 0);
            // Spread over orders of magnitude, as radiance is.
            Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10f32.powf(4.0 * s.next_1d() - 2.0)
        })
        .collect()
}

fn max_abs(v: &[Vec3]) -> f32 {
    v.iter().map(|c| c.abs().max_element()).fold(0.0, f32::max)
}

#[test]
fn round_trip_is_exact_to_1e6() {
    for (n, seed) in [(1, 1), (2, 2), (8, 3), (32, 4), (64, 5)] {
        let img = random_image(n, seed);
        let back = Haar2d::forward(&img, n).inverse();
        let scale = max_abs(&img);
        for (a, b) in img.iter().zip(&back) {
            assert!(
                (*a - *b).abs().max_element() <= 1e-6 * scale,
                "n = {n}: {a} came back as {b}"
            );
        }
    }
}

#[test]
fn parseval_energy_is_preserved() {
    for (n, seed) in [(2, 6), (16, 7), (64, 8)] {
        let img = random_image(n, seed);
        let h = Haar2d::forward(&img, n);
        for c in 0..3 {
            // ‖f‖² over the unit square: each texel covers 1/N².
            let space: f64 =
                img.iter().map(|v| (v[c] as f64).powi(2)).sum::<f64>() / (n * n) as f64;
            let coeffs: f64 = (h.scale[c] as f64).powi(2)
                + h.details
                    .iter()
                    .flat_map(|d| d.iter().map(move |v| (v[c] as f64).powi(2)))
                    .sum::<f64>();
            // Each coefficient carries ≤ J+1 f32 roundings (3.6e-7 relative at J = 6), so the
            // energies agree to about twice that.
            assert!(
                (space - coeffs).abs() <= 2e-6 * space,
                "n = {n}, channel {c}: {space} vs {coeffs}"
            );
        }
    }
}

#[test]
fn point_evaluation_equals_the_texel_value() {
    for (n, seed) in [(1, 9), (4, 10), (32, 11)] {
        let img = random_image(n, seed);
        let h = Haar2d::forward(&img, n);
        let scale = max_abs(&img);
        for y in 0..n {
            for x in 0..n {
                // Centre and a point near a corner of the texel.
                for (fx, fy) in [(0.5, 0.5), (0.01, 0.99)] {
                    let v = h.eval((x as f32 + fx) / n as f32, (y as f32 + fy) / n as f32);
                    let t = img[y * n + x];
                    assert!(
                        (v - t).abs().max_element() <= 1e-6 * scale,
                        "({x}, {y}): {v} vs {t}"
                    );
                }
            }
        }
    }
}

/// The map is bijective: square → sphere → square and sphere → square → sphere return the start.
#[test]
fn octahedral_map_is_bijective() {
    let mut s = Sampler::new(12, 0, 0);
    for _ in 0..100_000 {
        let p = s.next_2d();
        let back = direction_to_square(square_to_direction(p));
        assert!((back - p).length() < 1e-6, "{p} → {back}");
        let w = square_to_direction(p);
        assert!((w.length() - 1.0).abs() < 1e-6);
        let w2 = square_to_direction(direction_to_square(w));
        assert!((w2 - w).length() < 1e-6, "{w} → {w2}");
    }
    // Distinct texel centres map to distinct directions, and back to their own texel.
    let n = 64;
    for y in 0..n {
        for x in 0..n {
            let c = Vec2::new((x as f32 + 0.5) / n as f32, (y as f32 + 0.5) / n as f32);
            assert_eq!(texel_of(square_to_direction(c), n), (x, y));
        }
    }
}

/// Equal area: |∂w/∂u × ∂w/∂v| = 4π everywhere (so an N × N texel subtends 4π/N²), measured by
/// central differences in f64 off the map's creases (the diamond edges, the axes and the
/// square's border, where the map is only piecewise smooth).
#[test]
fn octahedral_map_is_equal_area() {
    let mut s = Sampler::new(13, 0, 0);
    let mut tested = 0;
    for _ in 0..20_000 {
        let p = s.next_2d().as_dvec2();
        let q = p * 2.0 - 1.0;
        let crease =
            q.x.abs()
                .min(q.y.abs())
                .min((1.0 - q.x.abs() - q.y.abs()).abs())
                .min(1.0 - q.x.abs())
                .min(1.0 - q.y.abs());
        // The map bends sharply near the poles (the centre and the corners, which are crease
        // crossings), so the step shrinks with the distance d to the nearest crease: the
        // difference error is O((h/d)²) = 1e-8, the rounding error O(1e-16/h) ≤ 1e-9.
        if crease < 1e-3 {
            continue;
        }
        let h = 1e-4 * crease / 2.0;
        let du = (square_to_direction_f64(p + DVec2::new(h, 0.0))
            - square_to_direction_f64(p - DVec2::new(h, 0.0)))
            / (2.0 * h);
        let dv = (square_to_direction_f64(p + DVec2::new(0.0, h))
            - square_to_direction_f64(p - DVec2::new(0.0, h)))
            / (2.0 * h);
        let j = du.cross(dv).length();
        assert!(
            (j - 4.0 * std::f64::consts::PI).abs() < 1e-6 * 4.0 * std::f64::consts::PI,
            "Jacobian {j} at {p}"
        );
        tested += 1;
    }
    assert!(tested > 19_000, "{tested} points tested");
}

/// And independently of any derivative: directions drawn uniformly on the sphere (by a method
/// that does not use the map) fall into the 16 × 16 texels equally often (Pearson, p ≥ 0.001).
#[test]
fn uniform_directions_fill_texels_uniformly() {
    let (n, draws) = (16u32, 1_000_000u64);
    let mut counts = vec![0u64; (n * n) as usize];
    for i in 0..draws {
        let w = square_to_uniform_sphere(Sampler::new(14, i, 0).next_2d());
        let (x, y) = texel_of(w, n);
        counts[(y * n + x) as usize] += 1;
    }
    let e = draws as f64 / (n * n) as f64;
    let chi2: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
    // 255 degrees of freedom: the 0.999 quantile is 330.5.
    assert!(chi2 < 330.5, "chi2 = {chi2} on 255 dof");
}

/// A glossy lobe on the octahedral map, as a surfel's outgoing radiance might be: mostly smooth,
/// with one sharp peak.
fn lobe_image(n: usize) -> Vec<Vec3> {
    let axis = Vec3::new(0.3, -0.2, 0.93).normalize();
    texel_directions(n.trailing_zeros())
        .iter()
        .map(|w| {
            let cos = w.dot(axis).max(0.0);
            Vec3::new(1.0, 0.8, 0.5) * (0.2 * cos + 5.0 * cos.powi(200))
        })
        .collect()
}

#[test]
fn sparse_tree_without_threshold_is_the_full_decomposition() {
    for n in [1, 2, 16] {
        let h = Haar2d::forward(&random_image(n, 20), n);
        let sparse = SparseHaar::compress(&h, 0.0);
        assert_eq!(sparse.to_dense(), h);
        let mut s = Sampler::new(21, n as u64, 0);
        for _ in 0..1000 {
            let p = s.next_2d();
            assert_eq!(sparse.eval(p.x, p.y), h.eval(p.x, p.y));
        }
    }
}

/// A thresholded map decodes the same, bit for bit, through the dense decomposition, through
/// its trimmed decomposition (coarser where the finer details were all dropped) and straight
/// from the sparse tree; and combining a trimmed map with a full one is combining the full
/// ones. The bounces read maps these shorter ways (src/bake/bounce/transport.rs, src/surfels/coding.rs).
#[test]
fn sparse_decodes_agree_bit_for_bit() {
    for (n, tau) in [
        (1usize, 0.0),
        (2, 0.0),
        (16, 0.0),
        (16, 0.05),
        (64, 0.01),
        (64, 0.3),
    ] {
        // An image constant over blocks of 4 × 4 texels has no finest two levels of detail.
        let coarse = random_image(n.div_ceil(4), 32);
        let blocky: Vec<Vec3> = (0..n * n)
            .map(|t| coarse[((t / n) / 4) * n.div_ceil(4) + (t % n) / 4])
            .collect();
        for (image, is_blocky) in [
            (random_image(n, 30), false),
            (lobe_image(n), false),
            (blocky, true),
        ] {
            let sparse = SparseHaar::compress(&Haar2d::forward(&image, n), tau);
            let full = sparse.to_dense();
            let texels = full.inverse();
            let trimmed = sparse.to_dense_trimmed();
            assert!(trimmed.levels <= full.levels);
            if is_blocky && n >= 16 {
                assert!(trimmed.levels <= full.levels - 2, "n {n}, tau {tau}");
            }
            assert_eq!(trimmed.refined_to(full.levels), full, "n {n}, tau {tau}");
            let mut direct = Vec::new();
            sparse.texels_into(&mut direct);
            assert_eq!(direct, texels, "n {n}, tau {tau}");
            let other = Haar2d::forward(&random_image(n, 31), n);
            assert_eq!(
                Haar2d::combine(&trimmed, 0.5, &other, -0.5),
                Haar2d::combine(&full, 0.5, &other, -0.5)
            );
            assert_eq!(
                SparseHaar::compress_below(&trimmed, 1e-3).refined_to(full.levels),
                SparseHaar::compress_below(&full, 1e-3)
            );
        }
    }
}

/// A map laid out for point lookups (the gather's) evaluates as its tree does, bit for bit,
/// at every point: inside texels, on their edges, at the square's edges and beyond them,
/// and at NaN. Full maps become texels, in less memory; a sharp lobe's deep, thin tree
/// stays a tree.
#[test]
fn point_maps_evaluate_as_their_trees_bit_for_bit() {
    let mut texels = 0;
    let mut trees = 0;
    for (n, tau) in [
        (1usize, 0.0),
        (2, 0.0),
        (8, 0.0),
        (16, 0.05),
        (64, 0.01),
        (64, 0.3),
    ] {
        for image in [random_image(n, 40), lobe_image(n)] {
            let sparse = SparseHaar::compress(&Haar2d::forward(&image, n), tau);
            let point = PointMap::from(sparse.clone());
            assert_eq!(point.levels(), sparse.levels());
            match &point {
                PointMap::Texels { .. } => texels += 1,
                PointMap::Tree(_) => trees += 1,
            }
            let mut s = Sampler::new(41, n as u64, 0);
            let mut points: Vec<Vec2> = (0..2000).map(|_| s.next_2d()).collect();
            // Texel edges at every level, the square's edges, outside it, and NaN.
            for k in 0..=2 * n {
                let e = k as f32 / (2 * n) as f32;
                points.extend([Vec2::new(e, 0.5), Vec2::new(0.5, e), Vec2::splat(e)]);
                points.push(Vec2::new(e, f32::from_bits(e.to_bits().saturating_sub(1))));
            }
            points.extend([
                Vec2::new(-0.25, 0.5),
                Vec2::new(1.5, -3.0),
                Vec2::new(f32::NAN, 0.5),
                Vec2::new(0.5, f32::INFINITY),
            ]);
            for p in points {
                let (a, b) = (point.eval(p.x, p.y), sparse.eval(p.x, p.y));
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    b.to_array().map(f32::to_bits),
                    "n {n}, tau {tau}, at {p}"
                );
            }
        }
    }
    // Both forms occur above: the full 8 × 8 map becomes texels, the 64 × 64 lobe at
    // tau 0.3 stays a tree.
    assert!(texels > 0 && trees > 0, "texels {texels}, trees {trees}");
}

/// Sums of sparse maps (the bounces' blends and totals, the tree's coding) are the dense
/// sums, thresholded the same way, bit for bit: terms of different resolutions and
/// thresholds, weights of either sign, and a map added to itself.
#[test]
fn sparse_sums_are_the_dense_sums_bit_for_bit() {
    let maps: Vec<SparseHaar<Vec3>> = [
        (64usize, 0.01, 40),
        (64, 0.1, 41),
        (16, 0.02, 42),
        (64, 0.0, 43),
    ]
    .iter()
    .map(|&(n, tau, seed)| {
        let image = if seed == 41 {
            lobe_image(n)
        } else {
            random_image(n, seed)
        };
        SparseHaar::compress(&Haar2d::forward(&image, n), tau)
    })
    .collect();
    let cases: Vec<Vec<(usize, f32)>> = vec![
        vec![(0, 1.0)],
        vec![(0, 1.0), (1, 0.37)],
        vec![(1, 0.25), (2, 0.5), (0, 0.125), (1, 0.125)],
        vec![(1, 0.5), (2, -0.5)],
        vec![(3, 1.0), (0, 1.0)],
    ];
    for terms in &cases {
        let sparse_terms: Vec<(&SparseHaar<Vec3>, f32)> =
            terms.iter().map(|&(m, w)| (&maps[m], w)).collect();
        let dense = terms
            .iter()
            .fold(Haar2d::forward(&[Vec3::ZERO], 1), |acc, &(m, w)| {
                Haar2d::combine(&acc, 1.0, &maps[m].to_dense_trimmed(), w)
            });
        let levels = terms
            .iter()
            .map(|&(m, _)| maps[m].levels())
            .max()
            .unwrap_or(0);
        for tau in [0.0, 1e-3, 0.05] {
            assert_eq!(
                SparseHaar::weighted_sum(&sparse_terms, tau),
                SparseHaar::compress(&dense, tau).refined_to(levels),
                "terms {terms:?}, tau {tau}"
            );
        }
        assert_eq!(SparseSum::of(&sparse_terms).norm(), dense.norm());
    }
    assert_eq!(
        SparseSum::of(&[(&maps[0], 1.0)]).norm(),
        maps[0].to_dense().norm()
    );
}

/// A map times a function constant on the cells of a coarser level (a surfel's radiance
/// times its projected area per 8² cell) equals the product taken texel by texel, to
/// rounding; the cells' means are the texels averaged.
#[test]
fn scaling_by_cells_is_the_texel_product() {
    for (n, k, tau) in [
        (64usize, 3u32, 0.01),
        (64, 3, 0.0),
        (16, 3, 0.05),
        (8, 3, 0.0),
        (32, 1, 0.02),
    ] {
        let map = SparseHaar::compress(&Haar2d::forward(&random_image(n, 50), n), tau);
        let side = 1usize << k;
        // Factors of both signs and zeros, as clamped cosines give.
        let factors: Vec<f32> = (0..side * side)
            .map(|c| ((c as f32 * 0.7).sin() * 1.5).max(-0.2))
            .collect();
        let mut texels = Vec::new();
        map.texels_into(&mut texels);
        let block = n / side;
        let mut means = Vec::new();
        map.means_into(k, &mut means);
        let mut product = texels.clone();
        for (t, v) in product.iter_mut().enumerate() {
            let cell = (t / n / block) * side + (t % n) / block;
            *v *= factors[cell];
        }
        for (c, mean) in means.iter().enumerate() {
            let (cx, cy) = (c % side, c / side);
            let mut sum = Vec3::ZERO;
            for y in cy * block..(cy + 1) * block {
                for x in cx * block..(cx + 1) * block {
                    sum += texels[y * n + x];
                }
            }
            let expected = sum / (block * block) as f32;
            assert!(
                (*mean - expected).abs().max_element() <= 1e-5 * max_abs(&texels),
                "mean {c}"
            );
        }
        let mut ours = Vec::new();
        map.scaled_by_cells(k, &factors).texels_into(&mut ours);
        let scale = max_abs(&product);
        for (a, b) in ours.iter().zip(&product) {
            assert!(
                (*a - *b).abs().max_element() <= 1e-5 * scale,
                "n {n}, k {k}: {a} against {b}"
            );
        }
    }
}

#[test]
fn thresholding_error_is_bounded_and_scale_free() {
    let n = 32;
    let img = lobe_image(n);
    let h = Haar2d::forward(&img, n);
    let total = 1 + h.details.len() * 3;
    for tau in [1e-4_f32, 1e-3, 1e-2] {
        let sparse = SparseHaar::compress(&h, tau);
        let kept = sparse.coefficient_count();
        let approx = sparse.to_dense().inverse();
        for c in 0..3 {
            let norm =
                (img.iter().map(|v| (v[c] as f64).powi(2)).sum::<f64>() / (n * n) as f64).sqrt();
            let err = (img
                .iter()
                .zip(&approx)
                .map(|(a, b)| ((a[c] - b[c]) as f64).powi(2))
                .sum::<f64>()
                / (n * n) as f64)
                .sqrt();
            // The module's bound, per channel, with the norm of the max-abs magnitudes (which
            // is at least each channel's norm).
            let bound = tau as f64 * h_norm(&h) * ((total - kept) as f64).sqrt();
            assert!(
                err <= bound + 1e-6 * norm,
                "tau {tau}, channel {c}: error {err} > bound {bound}"
            );
        }
        // Point evaluation agrees with the thresholded image.
        for (k, v) in approx.iter().enumerate() {
            let (x, y) = ((k % n) as f32 + 0.5, (k / n) as f32 + 0.5);
            let e = sparse.eval(x / n as f32, y / n as f32);
            assert!((e - *v).abs().max_element() <= 1e-5 * max_abs(&img));
        }
        // Scaling the function by 10^6 keeps the same coefficients, scaled.
        let big: Vec<Vec3> = img.iter().map(|v| *v * 1e6).collect();
        let sparse_big = SparseHaar::compress(&Haar2d::forward(&big, n), tau);
        assert_eq!(sparse_big.coefficient_count(), kept);
        // Coefficients agree to f32 rounding of the function's scale (a coefficient that is
        // itself cancellation noise cannot be compared relative to its own size).
        let (a, b) = (sparse.to_dense(), sparse_big.to_dense());
        let tol = 1e-6 * h_norm(&b) as f32;
        for (da, db) in a.details.iter().zip(&b.details) {
            for (ca, cb) in da.iter().zip(db) {
                assert!((*ca * 1e6 - *cb).abs().max_element() <= tol);
            }
        }
        eprintln!("tau {tau}: {kept} of {total} coefficients kept");
    }
    // It compresses, more with a larger tau (572, 402 and 85 of 1024 kept when written; the
    // horizon's kink crosses the map diagonally and keeps details all along it).
    let counts: Vec<usize> = [1e-4_f32, 1e-3, 1e-2]
        .iter()
        .map(|&t| SparseHaar::compress(&h, t).coefficient_count())
        .collect();
    assert!(counts[0] < total && counts[1] < counts[0] && counts[2] < counts[1]);
    assert!(counts[2] * 4 < total);
}

fn h_norm(h: &Haar2d<Vec3>) -> f64 {
    (std::iter::once(h.scale)
        .chain(h.details.iter().flat_map(|d| d.iter().copied()))
        .map(|c| (c.abs().max_element() as f64).powi(2))
        .sum::<f64>())
    .sqrt()
}

/// The cache encoding of sparse trees round-trips, scalar and RGB, and damaged or cut-off data
/// is refused rather than misread.
#[test]
fn sparse_tree_encoding_round_trips_and_refuses_damage() {
    let n = 16;
    let rgb = SparseHaar::compress(&Haar2d::forward(&lobe_image(n), n), 1e-3);
    let scalar_img: Vec<f32> = lobe_image(n).iter().map(|v| v.x).collect();
    let scalar = SparseHaar::compress(&Haar2d::forward(&scalar_img, n), 1e-3);
    let mut bytes = Vec::new();
    rgb.write_to(&mut bytes);
    let split = bytes.len();
    scalar.write_to(&mut bytes);
    let (a, used) = SparseHaar::<Vec3>::read_from(&bytes).expect("rgb tree");
    assert_eq!((a, used), (rgb.clone(), split));
    let (b, used) = SparseHaar::<f32>::read_from(&bytes[split..]).expect("scalar tree");
    // The lengths the writer reserves are the lengths it writes.
    assert_eq!(
        (rgb.encoded_len(), scalar.encoded_len()),
        (split, bytes.len() - split)
    );
    assert_eq!((b, used), (scalar, bytes.len() - split));
    // Every truncation of the first tree is refused.
    for len in 0..split {
        assert!(
            SparseHaar::<Vec3>::read_from(&bytes[..len]).is_none(),
            "cut at {len}"
        );
    }
    // A child mask with a bit beyond the four quadrants, or a NaN coefficient, is refused.
    let first_mask = 8 + 12;
    let mut bad = bytes[..split].to_vec();
    bad[first_mask] |= 0x10;
    assert!(SparseHaar::<Vec3>::read_from(&bad).is_none());
    let mut nan = bytes[..split].to_vec();
    nan[8..12].copy_from_slice(&f32::NAN.to_le_bytes());
    assert!(SparseHaar::<Vec3>::read_from(&nan).is_none());
}
