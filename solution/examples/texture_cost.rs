//! What a texture costs in a solution file and at load: PNG bytes per texel
//! (against the fixed 0.5 B of BC1 and 1 B of BC7) and the time to encode,
//! decode and build the mip chain, for three 1024² RGBA8 images: uniform
//! noise (incompressible), a smooth gradient and a checkerboard.
//!
//! `cargo run --release -p solution --example texture_cost`

use solution::format::{decode_png, encode_png, Texture};
use solution::texture::MipChain;
use std::time::Instant;

fn image(n: u32, mut texel: impl FnMut(u32, u32) -> [u8; 4]) -> Texture {
    let rgba = (0..n * n).flat_map(|k| texel(k % n, k / n)).collect();
    Texture {
        width: n,
        height: n,
        rgba,
    }
}

fn main() {
    let n = 1024;
    let mut state = 12345u32;
    let noise = image(n, |_, _| {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        let b = state.to_le_bytes();
        [b[3], b[2], b[1], 255]
    });
    let gradient = image(n, |x, y| {
        [(x / 4) as u8, (y / 4) as u8, ((x + y) / 8) as u8, 255]
    });
    let checker = image(n, |x, y| {
        let v = if (x / 64 + y / 64) % 2 == 0 { 230 } else { 40 };
        [v, v, v, 255]
    });
    println!("texture (1024²)  png_bytes  bytes/texel  encode_ms  decode_ms  mips_ms");
    for (name, texture) in [
        ("noise", noise),
        ("gradient", gradient),
        ("checker", checker),
    ] {
        let start = Instant::now();
        let png = encode_png(&texture).expect("encodes");
        let encoded = start.elapsed();
        let start = Instant::now();
        let back = decode_png(&png, n, n).expect("decodes");
        let decoded = start.elapsed();
        assert_eq!(back, texture);
        let start = Instant::now();
        let chain = MipChain::new(&back);
        let mips = start.elapsed();
        assert_eq!(chain.levels().len(), 11);
        println!(
            "{name:<16} {:>9}  {:>11.3}  {:>9.1}  {:>9.1}  {:>7.1}",
            png.len(),
            png.len() as f64 / f64::from(n * n),
            encoded.as_secs_f64() * 1e3,
            decoded.as_secs_f64() * 1e3,
            mips.as_secs_f64() * 1e3,
        );
    }
}
