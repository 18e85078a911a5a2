//! Tests of the global-cube gather: see [`super`].

use super::*;

#[test]
#[ignore]
fn probe_table() {
    for alpha in [0.1, 0.3] {
        for n in [17usize, 33, 65, 129] {
            let t = std::time::Instant::now();
            let table: Vec<f64> = (0..n)
                .map(|j| crate::brdf::exact_hemisphere_integral(alpha, j as f64 / (n - 1) as f64))
                .collect();
            let el = t.elapsed().as_secs_f64();
            let mut worst = (0.0, 0.0);
            for j in 0..n - 1 {
                let mu = (j as f64 + 0.5) / (n - 1) as f64;
                let direct = crate::brdf::exact_hemisphere_integral(alpha, mu);
                let lin = 0.5 * (table[j] + table[j + 1]);
                let e = (lin - direct).abs() / direct;
                if e > worst.0 {
                    worst = (e, mu);
                }
            }
            println!("alpha {alpha} n {n}: {el:.3}s linear-mid worst {:.2e} at {:.3}, S(0)={:.4e} S(1)={:.4e}", worst.0, worst.1, table[0], table[n-1]);
        }
    }
}
