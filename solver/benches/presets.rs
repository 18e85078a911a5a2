//! Preset benchmark (written once the solver core lands).
fn main() {
    eprintln!("benches/presets: waiting for the solver core");
}
