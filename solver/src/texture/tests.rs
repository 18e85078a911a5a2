use super::*;

/// sRGB 128 decoded: ((128/255 + 0.055) / 1.055)^2.4 = 0.21586 (IEC 61966-2-1).
const GREY_128: f64 = 0.215_860_5;

/// A `size` × `size` texture: grey 128 on the left half, white on the right.
fn half_grey(size: usize) -> Texture {
    let mut rgb = Vec::with_capacity(size * size * 3);
    for _ in 0..size {
        for x in 0..size {
            let code = if x < size / 2 { 128 } else { 255 };
            rgb.extend([code; 3]);
        }
    }
    Texture::from_srgb(size, size, &rgb, 3).unwrap()
}

fn uv(u: f64, v: f64) -> DVec2 {
    DVec2::new(u, v)
}

#[test]
fn srgb_decoding_matches_the_standard() {
    assert!((f64::from(srgb_to_linear(128)) - GREY_128).abs() < 1e-6);
    assert_eq!(srgb_to_linear(0), 0.0);
    assert_eq!(srgb_to_linear(255), 1.0);
    // The linear segment: 10 / 255 / 12.92.
    assert!((f64::from(srgb_to_linear(10)) - 10.0 / 255.0 / 12.92).abs() < 1e-7);
}

#[test]
fn an_element_over_a_grey_half_and_a_white_half_gets_their_linear_mean() {
    // The triangle is symmetric about u = 0.5, so half its area is grey and
    // half white: albedo (0.216 + 1) / 2 = 0.608. Without the sRGB decode it
    // would be (0.502 + 1) / 2 = 0.751. Tolerance 1e-3 (the issue's); the
    // integral is exact up to rounding, so 1e-6 is asserted.
    let texture = half_grey(64);
    let expected = (GREY_128 + 1.0) / 2.0;
    let whole = texture.integrate([uv(0.0, 0.0), uv(1.0, 0.0), uv(0.5, 1.0)]);
    assert!(
        (whole.mean - DVec3::splat(expected)).abs().max_element() < 1e-6,
        "{whole:?}"
    );
    // 64² texels under a 65 × 65 cell box exceeds MAX_CELLS: level 1 is used.
    assert_eq!(whole.level, 1);
    let sum: DVec3 = whole.corner.iter().sum();
    assert!((sum - whole.mean).abs().max_element() < 1e-12);
}

#[test]
fn the_same_holds_for_elements_between_and_at_coarser_mip_levels() {
    // A 256² texture and triangles, symmetric about u = 0.5, whose sizes put
    // their footprints between levels (level 0 to 3): each is integrated at
    // one level exactly, and every level keeps the half/half split because
    // the boundary (texel 128) stays on a texel edge down to 2 × 2.
    let texture = half_grey(256);
    let expected = (GREY_128 + 1.0) / 2.0;
    let mut levels = Vec::new();
    for half_width in [0.1, 0.17, 0.3, 0.43] {
        let t = [
            uv(0.5 - half_width, 0.2),
            uv(0.5 + half_width, 0.2),
            uv(0.5, 0.2 + 1.7 * half_width),
        ];
        let i = texture.integrate(t);
        assert!(
            (i.mean - DVec3::splat(expected)).abs().max_element() < 1e-3,
            "half width {half_width}: {i:?}"
        );
        levels.push(i.level);
    }
    // The bounding boxes span 52 × 45, 88 × 75 (level 1: 44 × 38), 154 × 131
    // (level 2: 38 × 33) and 220 × 187 (level 2: 55 × 47) texels of level 0.
    assert_eq!(levels, vec![0, 1, 2, 2], "the footprints straddle levels");
}

#[test]
fn corner_weights_follow_the_albedo_under_each_corner() {
    // Grey left, white right; a triangle with corner 1 deep in the white half.
    // The white corner's weight must exceed the grey corners'; for a uniform
    // texture each corner gets exactly mean / 3.
    let texture = half_grey(32);
    let i = texture.integrate([uv(0.1, 0.1), uv(0.9, 0.5), uv(0.1, 0.9)]);
    assert!(i.corner[1].x > i.corner[0].x && i.corner[1].x > i.corner[2].x);
    let white = Texture::from_srgb(4, 4, &[255; 48], 3).unwrap();
    let u = white.integrate([uv(0.1, 0.1), uv(0.9, 0.5), uv(0.1, 0.9)]);
    for c in u.corner {
        assert!((c - DVec3::splat(1.0 / 3.0)).abs().max_element() < 1e-12);
    }
}

#[test]
fn the_pyramid_keeps_the_mean_for_odd_sizes() {
    // A 5 × 3 texture of distinct values: every level's mean (area-weighted)
    // equals level 0's, since the box filter's weights per source texel sum
    // to the destination's share of the area.
    let rgb: Vec<u8> = (0..45u32).map(|k| (k * 37 % 251) as u8).collect();
    let texture = Texture::from_srgb(5, 3, &rgb, 3).unwrap();
    let mean = |l: &Level| {
        l.texels
            .iter()
            .map(|t| DVec3::from_array(t.map(f64::from)))
            .sum::<DVec3>()
            / l.texels.len() as f64
    };
    let m0 = mean(&texture.levels[0]);
    for l in &texture.levels {
        assert!((mean(l) - m0).abs().max_element() < 1e-6, "{l:?}");
    }
    assert_eq!(texture.levels.last().unwrap().texels.len(), 1);
}

#[test]
fn wrapping_degenerate_and_huge_triangles_stay_finite() {
    let texture = half_grey(8);
    // Shifted by whole repeats: the same integral.
    let a = texture.integrate([uv(0.1, 0.1), uv(0.9, 0.2), uv(0.3, 0.8)]);
    let b = texture.integrate([uv(3.1, -1.9), uv(3.9, -1.8), uv(3.3, -1.2)]);
    assert!((a.mean - b.mean).abs().max_element() < 1e-9);
    // A zero-area UV triangle: the bilinear sample, finite.
    let d = texture.integrate([uv(0.7, 0.5); 3]);
    assert!((d.mean - DVec3::ONE).abs().max_element() < 1e-9, "{d:?}");
    // A triangle spanning 10⁶ repeats: the texture's mean.
    let h = texture.integrate([uv(0.0, 0.0), uv(1e6, 0.0), uv(0.0, 1e6)]);
    assert!((h.mean - texture.mean()).abs().max_element() < 1e-9);
    assert!(
        (texture.mean() - DVec3::splat((GREY_128 + 1.0) / 2.0))
            .abs()
            .max_element()
            < 1e-6
    );
    // NaN UVs: the mean, not a panic.
    let n = texture.integrate([uv(f64::NAN, 0.0), uv(1.0, 0.0), uv(0.0, 1.0)]);
    assert!(n.mean.is_finite());
}

#[test]
fn bilinear_reads_texel_centres_exactly() {
    // Texel (x, y) has its centre at u = (x + 0.5) / w, v = 1 − (y + 0.5) / h.
    let texture = half_grey(4);
    let grey = texture.bilinear(uv(0.125, 0.875));
    let white = texture.bilinear(uv(0.875, 0.125));
    assert!((grey.x - GREY_128).abs() < 1e-6);
    assert!((white.x - 1.0).abs() < 1e-6);
    // Halfway between texel centres 1 and 2 (the boundary): their mean.
    let mid = texture.bilinear(uv(0.5, 0.5));
    assert!((mid.x - (GREY_128 + 1.0) / 2.0).abs() < 1e-6);
}
