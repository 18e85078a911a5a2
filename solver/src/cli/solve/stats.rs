//! The closing summary of a solve, for people (stderr) and for scripts (`--stats-json`).

use serde::Serialize;

/// The figures of a finished (or stopped) solve. The JSON keys are a contract with
/// scripts and benchmarks: exactly these eight.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RunStats {
    pub elements: u64,
    pub vertices: u64,
    pub shots: u64,
    /// Visibility rays traced, over every session of a resumed solve.
    pub rays: u64,
    /// Wall-clock seconds, over every session of a resumed solve.
    pub seconds: f64,
    /// `rays / seconds`.
    pub rays_per_second: f64,
    /// Worker threads of the last session.
    pub threads: usize,
    /// Total unshot power / total emitted power at the end.
    pub unshot_fraction: f64,
}

impl RunStats {
    /// One line for people.
    pub fn summary(&self, threshold: f64) -> String {
        use super::eta::{format_count, format_duration};
        format!(
            "{} elements, {} vertices, {} shots, {} rays in {} ({:.3} s; {} rays/s on {} \
             thread{}); unshot {:.4}% of emitted power (threshold {}%)",
            self.elements,
            self.vertices,
            self.shots,
            format_count(self.rays as f64),
            format_duration(self.seconds),
            self.seconds,
            format_count(self.rays_per_second),
            self.threads,
            if self.threads == 1 { "" } else { "s" },
            100.0 * self.unshot_fraction,
            100.0 * threshold,
        )
    }

    /// The JSON object of `--stats-json`, pretty-printed.
    pub fn to_json(&self) -> String {
        // Serializing a struct of numbers cannot fail; NaN (no emitter) becomes null.
        serde_json::to_string_pretty(self).unwrap_or_default() + "\n"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_has_exactly_the_contract_keys() {
        let stats = RunStats {
            elements: 1,
            vertices: 2,
            shots: 3,
            rays: 4,
            seconds: 0.5,
            rays_per_second: 8.0,
            threads: 2,
            unshot_fraction: 0.01,
        };
        let value: serde_json::Value = serde_json::from_str(&stats.to_json()).unwrap();
        let mut keys: Vec<_> = value.as_object().unwrap().keys().cloned().collect();
        keys.sort();
        assert_eq!(
            keys,
            [
                "elements",
                "rays",
                "rays_per_second",
                "seconds",
                "shots",
                "threads",
                "unshot_fraction",
                "vertices"
            ]
        );
        assert_eq!(value["rays_per_second"], 8.0);
    }
}
