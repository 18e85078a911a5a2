//! Tests of the SH basis against mathematics: closed forms, orthonormality by exact
//! quadrature, the addition theorem, finiteness at the extremes and the f32 twin.

use super::*;

/// A small deterministic generator (xorshift64*) so that tests need no crate.
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform on the unit sphere.
    fn direction(&mut self) -> DVec3 {
        let z = 2.0 * self.next_f64() - 1.0;
        let phi = 2.0 * PI * self.next_f64();
        let s = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

/// Directions that stress the recurrences: poles, equator, near-poles.
fn special_directions() -> Vec<DVec3> {
    let mut v = vec![
        DVec3::Z,
        -DVec3::Z,
        DVec3::X,
        DVec3::Y,
        -DVec3::X,
        DVec3::new(1.0, 1.0, 0.0).normalize(),
        DVec3::new(-1.0, 0.3, 0.0).normalize(),
    ];
    for eps in [1e-3, 1e-6, 1e-9, 1e-150, 1e-300] {
        v.push(DVec3::new(eps, 0.0, 1.0).normalize());
        v.push(DVec3::new(eps, eps, -1.0).normalize());
        v.push(DVec3::new(1.0, 0.0, eps).normalize());
    }
    v
}

#[test]
fn index_round_trip() {
    let mut k = 0;
    for l in 0..=40u32 {
        for m in -(l as i32)..=(l as i32) {
            assert_eq!(index(l, m), k);
            assert_eq!(degree_order(k), (l, m));
            k += 1;
        }
    }
    assert_eq!(coefficient_count(40), k);
    assert_eq!(coefficient_count(0), 1);
    assert_eq!(coefficient_count(25), 676);
    assert_eq!(coefficient_count(64), 4225);
}

#[test]
fn closed_forms_up_to_degree_3() {
    // Real orthonormal SH without the Condon–Shortley phase, written out in
    // Cartesian form. Tolerance 1e-12: the recurrences take < 10 roundings of
    // values ≤ 1, so the error is ~1e-15; 1e-12 leaves room without hiding a wrong
    // constant (the smallest constant difference that matters is ~1e-2).
    type ClosedForm = (u32, i32, fn(f64, f64, f64) -> f64);
    let forms: Vec<ClosedForm> = vec![
        (0, 0, |_, _, _| 0.5 * (1.0 / PI).sqrt()),
        (1, -1, |_, y, _| (3.0 / (4.0 * PI)).sqrt() * y),
        (1, 0, |_, _, z| (3.0 / (4.0 * PI)).sqrt() * z),
        (1, 1, |x, _, _| (3.0 / (4.0 * PI)).sqrt() * x),
        (2, -2, |x, y, _| 0.5 * (15.0 / PI).sqrt() * x * y),
        (2, -1, |_, y, z| 0.5 * (15.0 / PI).sqrt() * y * z),
        (2, 0, |_, _, z| {
            0.25 * (5.0 / PI).sqrt() * (3.0 * z * z - 1.0)
        }),
        (2, 1, |x, _, z| 0.5 * (15.0 / PI).sqrt() * x * z),
        (2, 2, |x, y, _| 0.25 * (15.0 / PI).sqrt() * (x * x - y * y)),
        (3, -3, |x, y, _| {
            0.25 * (35.0 / (2.0 * PI)).sqrt() * y * (3.0 * x * x - y * y)
        }),
        (3, -2, |x, y, z| 0.5 * (105.0 / PI).sqrt() * x * y * z),
        (3, -1, |_, y, z| {
            0.25 * (21.0 / (2.0 * PI)).sqrt() * y * (5.0 * z * z - 1.0)
        }),
        (3, 0, |_, _, z| {
            0.25 * (7.0 / PI).sqrt() * (5.0 * z * z * z - 3.0 * z)
        }),
        (3, 1, |x, _, z| {
            0.25 * (21.0 / (2.0 * PI)).sqrt() * x * (5.0 * z * z - 1.0)
        }),
        (3, 2, |x, y, z| {
            0.25 * (105.0 / PI).sqrt() * (x * x - y * y) * z
        }),
        (3, 3, |x, y, _| {
            0.25 * (35.0 / (2.0 * PI)).sqrt() * x * (x * x - 3.0 * y * y)
        }),
    ];
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut out = vec![0.0; coefficient_count(3)];
    let mut dirs = special_directions();
    dirs.extend((0..1000).map(|_| rng.direction()));
    for d in dirs {
        eval_basis(3, d, &mut out);
        for (l, m, f) in &forms {
            let expect = f(d.x, d.y, d.z);
            let got = out[index(*l, *m)];
            assert!(
                (got - expect).abs() < 1e-12,
                "Y_{l},{m}({d}) = {got}, closed form {expect}"
            );
        }
    }
}

/// Gauss–Legendre in cos θ with L+1 nodes (exact to degree 2L+1) times a uniform
/// rule of 2L+1 points in φ (exact for frequencies up to 2L): exact for every
/// product Y_lm·Y_l'm' with l, l' ≤ L. Calls `visit(weight, ring_of_basis_values)`
/// once per ring of constant z with the basis of each φ sample.
fn for_each_ring(order: u32, mut visit: impl FnMut(f64, &[Vec<f64>])) {
    let n_phi = 2 * order as usize + 1;
    let (zs, ws) = gauss_legendre(order as usize + 1);
    let count = coefficient_count(order);
    let mut ring = vec![vec![0.0; count]; n_phi];
    for (z, w) in zs.iter().zip(&ws) {
        let s = (1.0 - z * z).sqrt();
        for (j, out) in ring.iter_mut().enumerate() {
            let phi = 2.0 * PI * (j as f64 + 0.5) / n_phi as f64;
            eval_basis(order, DVec3::new(s * phi.cos(), s * phi.sin(), *z), out);
        }
        visit(w * 2.0 * PI / n_phi as f64, &ring);
    }
}

#[test]
fn orthonormal_full_gram_matrix_up_to_order_20() {
    // Every pair (k, k') for L = 20 (441 functions). The quadrature is exact, so
    // the only error is rounding: ~1e-15 per term times ~1e3 terms; 1e-10 is the
    // tolerance the brief asks for and is still 1e5 above that.
    let order = 20;
    let n = coefficient_count(order);
    let mut gram = vec![0.0; n * n];
    for_each_ring(order, |w, ring| {
        for y in ring {
            for a in 0..n {
                let wa = w * y[a];
                for b in a..n {
                    gram[a * n + b] += wa * y[b];
                }
            }
        }
    });
    for a in 0..n {
        for b in a..n {
            let expect = if a == b { 1.0 } else { 0.0 };
            let g = gram[a * n + b];
            assert!(
                (g - expect).abs() < 1e-10,
                "<Y{:?}, Y{:?}> = {g}",
                degree_order(a),
                degree_order(b)
            );
        }
    }
}

#[test]
fn orthonormal_up_to_order_64() {
    // At L = 64 (4225 functions) the full Gram matrix costs 1.5e11 products, so this
    // checks (a) every pair with the same signed m (the pairs the l-recurrence
    // builds, where an error in a_lm, b_lm would show) and (b) 3000 random pairs of
    // any (l, m), all with the same exact quadrature as the full test above.
    let order = 64u32;
    let n = coefficient_count(order);
    let mut rng = Rng(99);
    let random_pairs: Vec<(usize, usize)> = (0..3000)
        .map(|_| {
            (
                (rng.next_f64() * n as f64) as usize,
                (rng.next_f64() * n as f64) as usize,
            )
        })
        .collect();
    let mut random_sums = vec![0.0; random_pairs.len()];
    // Block per signed m: indices of Y_lm, l = |m|..=L; upper triangle of its Gram.
    let blocks: Vec<Vec<usize>> = (-(order as i32)..=order as i32)
        .map(|m| (m.unsigned_abs()..=order).map(|l| index(l, m)).collect())
        .collect();
    let mut block_gram: Vec<Vec<f64>> = blocks
        .iter()
        .map(|b| vec![0.0; b.len() * b.len()])
        .collect();
    let mut columns = vec![0.0; n * (2 * order as usize + 1)];
    for_each_ring(order, |w, ring| {
        let n_phi = ring.len();
        // Transpose to basis-major so that each pair is a contiguous dot product.
        for (j, y) in ring.iter().enumerate() {
            for k in 0..n {
                columns[k * n_phi + j] = y[k];
            }
        }
        let col = |k: usize| &columns[k * n_phi..(k + 1) * n_phi];
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        for (block, gram) in blocks.iter().zip(block_gram.iter_mut()) {
            let len = block.len();
            for i in 0..len {
                let ci = col(block[i]);
                for j in i..len {
                    gram[i * len + j] += w * dot(ci, col(block[j]));
                }
            }
        }
        for ((a, b), sum) in random_pairs.iter().zip(random_sums.iter_mut()) {
            *sum += w * dot(col(*a), col(*b));
        }
    });
    // Same 1e-10 as above; at L = 64 each entry sums 8385 terms of size ≤ 10.
    for (block, gram) in blocks.iter().zip(&block_gram) {
        let len = block.len();
        for i in 0..len {
            for j in i..len {
                let expect = if i == j { 1.0 } else { 0.0 };
                let g = gram[i * len + j];
                assert!(
                    (g - expect).abs() < 1e-10,
                    "<Y{:?}, Y{:?}> = {g}",
                    degree_order(block[i]),
                    degree_order(block[j])
                );
            }
        }
    }
    for ((a, b), g) in random_pairs.iter().zip(&random_sums) {
        let expect = if a == b { 1.0 } else { 0.0 };
        assert!(
            (g - expect).abs() < 1e-10,
            "<Y{:?}, Y{:?}> = {g}",
            degree_order(*a),
            degree_order(*b)
        );
    }
}

#[test]
fn addition_theorem_up_to_order_64() {
    // Σ_m Y_lm(a) Y_lm(b) = (2l+1)/(4π) P_l(a·b). Both sides are O((2l+1)/(4π)) ≤ 10.3
    // at l = 64; rounding in the recurrences and the sum of 129 terms gives ~1e-13
    // relative, so 1e-10 × (2l+1)/(4π) is the stated bound.
    let order = 64u32;
    let mut rng = Rng(7);
    let mut ya = vec![0.0; coefficient_count(order)];
    let mut yb = vec![0.0; coefficient_count(order)];
    let mut p = vec![0.0; order as usize + 1];
    let specials = special_directions();
    let mut pairs: Vec<(DVec3, DVec3)> = (0..300)
        .map(|_| (rng.direction(), rng.direction()))
        .collect();
    for a in &specials {
        pairs.push((*a, *a));
        pairs.push((*a, rng.direction()));
        pairs.push((*a, -*a));
    }
    for (a, b) in pairs {
        eval_basis(order, a, &mut ya);
        eval_basis(order, b, &mut yb);
        legendre_all(order, a.dot(b).clamp(-1.0, 1.0), &mut p);
        for l in 0..=order {
            let sum: f64 = (-(l as i32)..=l as i32)
                .map(|m| ya[index(l, m)] * yb[index(l, m)])
                .sum();
            let scale = (2.0 * l as f64 + 1.0) / (4.0 * PI);
            let expect = scale * p[l as usize];
            assert!(
                (sum - expect).abs() < 1e-10 * scale,
                "l={l} a={a} b={b}: {sum} vs {expect}"
            );
        }
    }
}

#[test]
fn finite_and_bounded_up_to_order_100_at_poles_equator_and_near_poles() {
    // No NaN or Inf, every |Y_lm| within Unsöld's envelope √((2l+1)/4π) (plus 1e-12
    // relative for rounding), and Σ_m Y_lm² = (2l+1)/(4π) within 1e-10 relative.
    let order = 100u32;
    let mut y = vec![0.0; coefficient_count(order)];
    let mut rng = Rng(3);
    let mut dirs = special_directions();
    dirs.extend((0..200).map(|_| rng.direction()));
    // Degenerate inputs are mapped to +z, not to NaN.
    dirs.push(DVec3::ZERO);
    dirs.push(DVec3::new(f64::NAN, 0.0, 1.0));
    for d in dirs {
        eval_basis(order, d, &mut y);
        for l in 0..=order {
            let env = envelope(l);
            let mut sum = 0.0;
            for m in -(l as i32)..=l as i32 {
                let v = y[index(l, m)];
                assert!(v.is_finite(), "Y_{l},{m}({d}) = {v}");
                assert!(
                    v.abs() <= env * (1.0 + 1e-12),
                    "Y_{l},{m}({d}) = {v} > {env}"
                );
                sum += v * v;
            }
            assert!(
                (sum - env * env).abs() < 1e-10 * env * env,
                "Unsöld l={l} d={d}: {sum}"
            );
        }
    }
    // At the poles only m = 0 survives and Y_l0(±z) = ±^l √((2l+1)/4π).
    eval_basis(order, -DVec3::Z, &mut y);
    for l in 0..=order {
        let sign = if l.is_multiple_of(2) { 1.0 } else { -1.0 };
        assert!((y[index(l, 0)] - sign * envelope(l)).abs() < 1e-12 * envelope(l));
    }
}

#[test]
fn orders_above_the_cached_table_agree_with_it() {
    // Orders > CACHED_ORDER compute the recurrence factors per term; the values must
    // be identical (same arithmetic) to the cached path's for l ≤ CACHED_ORDER.
    let mut rng = Rng(5);
    let hi = CACHED_ORDER + 2;
    let mut a = vec![0.0; coefficient_count(CACHED_ORDER)];
    let mut b = vec![0.0; coefficient_count(hi)];
    for _ in 0..5 {
        let d = rng.direction();
        eval_basis(CACHED_ORDER, d, &mut a);
        eval_basis(hi, d, &mut b);
        assert_eq!(&a[..], &b[..a.len()]);
        assert!(b.iter().all(|v| v.is_finite()));
    }
}

/// The f32 basis (what the runtime's shader computes) against f64 at the largest
/// order any file may hold, `format::MAX_SH_ORDER` = 64. Tolerance, stated per
/// value: `|Y_lm^f32 − Y_lm^f64| ≤ f32_basis_tolerance(l)` = 4ε·(l + 1)²·envelope(l)
/// with ε = 2⁻²⁴ (derivation at [`F32_BASIS_REL_TOLERANCE`]): 1.0e-3 of the
/// envelope at l = 64.
#[test]
fn f32_matches_f64_within_stated_tolerance() {
    let order = crate::format::MAX_SH_ORDER;
    let mut rng = Rng(11);
    let mut y64 = vec![0.0; coefficient_count(order)];
    let mut y32 = vec![0.0f32; coefficient_count(order)];
    let mut dirs = special_directions();
    dirs.extend((0..20_000).map(|_| rng.direction()));
    // Worst err / ((l+1)²·envelope(l)), the quantity F32_BASIS_REL_TOLERANCE bounds.
    let mut worst = 0.0f64;
    let mut per_l = vec![0.0f64; order as usize + 1];
    for d in dirs {
        // The f32 path sees the direction rounded to f32; compare against f64 at
        // that same (widened) direction so that only evaluation error is measured.
        let d32 = d.as_vec3();
        eval_basis_f32(order, d32, &mut y32);
        eval_basis(order, d32.as_dvec3(), &mut y64);
        for k in 0..y64.len() {
            let (l, _) = degree_order(k);
            assert!(y32[k].is_finite());
            let err = (f64::from(y32[k]) - y64[k]).abs();
            let l1 = l as f64 + 1.0;
            worst = worst.max(err / (l1 * l1 * envelope(l)));
            per_l[l as usize] = per_l[l as usize].max(err / envelope(l));
            assert!(
                err <= f32_basis_tolerance(l),
                "k={k} d={d}: f32 {} vs f64 {}",
                y32[k],
                y64[k]
            );
        }
    }
    println!("worst f32 error / ((l+1)²·envelope(l)) up to L={order}: {worst:.3e}");
    for (l, e) in per_l.iter().enumerate() {
        let ratio = e / (f64::from(f32::EPSILON / 2.0) * ((l + 1) * (l + 1)) as f64);
        println!("l={l}: max |ΔY|/envelope = {e:.3e} = {ratio:.2}·ε·(l+1)²");
    }
}

#[test]
fn eval_rgb_uses_the_file_layout() {
    // coefficients[k * 3 + c]: put Y_1,1 (∝ x) in blue and Y_0,0 in red only.
    let order = 2;
    let mut c = vec![0.0f32; coefficient_count(order) * 3];
    c[index(1, 1) * 3 + 2] = 1.0;
    c[index(0, 0) * 3] = 2.0;
    let d = DVec3::new(0.6, 0.0, 0.8);
    let rgb = eval_rgb(order, &c, d);
    // 2.0 · Y00 and √(3/4π)·0.6, rounding only.
    assert!((rgb[0] - 2.0 * Y00).abs() < 1e-15);
    assert_eq!(rgb[1], 0.0);
    assert!((rgb[2] - (3.0 / (4.0 * PI)).sqrt() * 0.6).abs() < 1e-15);
    // Clamped evaluation: a negative channel shows as 0, positive ones unchanged.
    let mut neg = c.clone();
    neg[index(0, 0) * 3 + 1] = -1.0;
    let clamped = eval_rgb_clamped(order, &neg, d);
    assert_eq!(clamped[1], 0.0);
    assert_eq!(clamped[0], eval_rgb(order, &neg, d)[0]);
    // A short slice is not a panic: missing coefficients count as zero.
    let short = eval_rgb(order, &c[..3], d);
    assert!((short[0] - 2.0 * Y00).abs() < 1e-15 && short[2] == 0.0);
}

#[test]
fn local_frame_axes_and_round_trip() {
    let n = DVec3::new(0.0, 1.0, 0.0);
    let t = DVec3::new(0.0, 0.0, -1.0);
    let b = n.cross(t);
    // θ from n, φ from t toward b: t → +x, b → +y, n → +z.
    assert!((to_local(t, n, t) - DVec3::X).length() < 1e-15);
    assert!((to_local(b, n, t) - DVec3::Y).length() < 1e-15);
    assert!((to_local(n, n, t) - DVec3::Z).length() < 1e-15);
    let mut rng = Rng(21);
    for _ in 0..100 {
        let (n, t) = orthonormal_frame(rng.direction(), rng.direction()).unwrap();
        assert!(n.dot(t).abs() < 1e-14 && (t.length() - 1.0).abs() < 1e-14);
        let d = rng.direction();
        assert!((from_local(to_local(d, n, t), n, t) - d).length() < 1e-14);
    }
    // A tangent parallel to the normal falls back to a fixed reference axis.
    let (n2, t2) = orthonormal_frame(DVec3::Z, DVec3::Z * 3.0).unwrap();
    assert!(n2.dot(t2).abs() < 1e-15 && (t2.length() - 1.0).abs() < 1e-15);
    assert!(orthonormal_frame(DVec3::ZERO, DVec3::X).is_none());
}

#[test]
fn zonal_rotated_reproduces_the_legendre_series_about_the_axis() {
    // A lobe Σ a_l P_l(ω·r) rotated to axis r must evaluate, through its SH, to
    // the Legendre series itself at any ω (addition theorem); rounding only, 1e-12
    // relative to Σ|a_l|.
    let order = 24u32;
    let a: Vec<f64> = (0..=order).map(|l| (-(l as f64) * 0.2).exp()).collect();
    let zonal = zonal_from_legendre(&a);
    let mut rng = Rng(31);
    let mut c = vec![0.0; coefficient_count(order)];
    let mut y = vec![0.0; coefficient_count(order)];
    let mut p = vec![0.0; order as usize + 1];
    let scale: f64 = a.iter().map(|v| v.abs()).sum();
    for _ in 0..50 {
        let r = rng.direction();
        zonal_rotated(order, &zonal, r, &mut c);
        let w = rng.direction();
        eval_basis(order, w, &mut y);
        let via_sh: f64 = c.iter().zip(&y).map(|(ci, yi)| ci * yi).sum();
        legendre_all(order, w.dot(r), &mut p);
        let direct: f64 = a.iter().zip(&p).map(|(ai, pi)| ai * pi).sum();
        assert!(
            (via_sh - direct).abs() < 1e-12 * scale,
            "{via_sh} vs {direct}"
        );
    }
    // About +z only the m = 0 coefficients survive, equal to `zonal`.
    zonal_rotated(order, &zonal, DVec3::Z, &mut c);
    for l in 0..=order {
        for m in -(l as i32)..=l as i32 {
            let expect = if m == 0 { zonal[l as usize] } else { 0.0 };
            assert!((c[index(l, m)] - expect).abs() < 1e-14);
        }
    }
}
