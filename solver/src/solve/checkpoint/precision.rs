//! The precision directional mode keeps its SH state at, so that its
//! checkpoints need not store noise.
//!
//! Why: a directional checkpoint is mostly f64 SH coefficients (each vertex's
//! radiance and each patch's unshot), and the low mantissa bytes of a sum of
//! thousands of f64 terms are noise to any lossless coder (measured: byte
//! planes 0–5 deflate to 0.96 of their size), while the solution file holds
//! f32. No part of the solve's result depends on bits below 2⁻⁴⁰ of a value
//! in any way that matters physically (the output is f32, 2⁻²⁴; the solve's
//! own error is ~1e-2), but the solve does read every bit it keeps, so a
//! checkpoint that dropped them would not resume bit for bit. Instead the
//! solve itself keeps [`KEPT_MANTISSA_BITS`]: each radiance coefficient is
//! rounded to nearest ([`round_to_kept`]) as a shot adds to it (a vertex that
//! refinement creates, at the end of that step), each patch's unshot as it is
//! gathered, and the initial emission too; a checkpoint stores that state
//! exactly. Its
//! [`DROPPED_BITS`] low bits are then zero, which the byte planes of
//! [`super::packed`] turn into runs that deflate to almost nothing, and a
//! resume reads back the very state the uninterrupted solve continues from.
//!
//! Cost in accuracy: each rounding moves a value by at most 2⁻⁴¹ of itself
//! (4.5e-13); over N shots the drift is at most N · 4.5e-13 (1e-9 after 2,000
//! shots, below the f32 output's 6e-8), in practice ~√N times that.
//!
//! The masks that turn shared high bits into zero bytes (the recorded-shot
//! part for the radiance, a prediction for the unshot) use only the kept bits
//! of their mask value ([`kept_bits`]), so they keep the low bits zero.

/// Mantissa bits kept of f64's 52 explicit ones.
pub const KEPT_MANTISSA_BITS: u32 = 40;

/// Low mantissa bits that are zero in the state a directional solve keeps.
pub const DROPPED_BITS: u32 = 52 - KEPT_MANTISSA_BITS;

const LOW: u64 = (1 << DROPPED_BITS) - 1;

/// `x` rounded to [`KEPT_MANTISSA_BITS`], to nearest with ties away from
/// zero: half a kept unit is added to the magnitude's bits and the dropped
/// bits cleared. A carry out of the mantissa correctly moves to the next
/// binade. Zero, subnormals' tiny remainders and non-finite values are left
/// as they are (0 stays 0; an infinity or NaN is never rounded to a number).
pub fn round_to_kept(x: f64) -> f64 {
    if !x.is_finite() {
        return x;
    }
    let rounded = f64::from_bits((x.to_bits() + (1 << (DROPPED_BITS - 1))) & !LOW);
    if rounded.is_finite() {
        rounded
    } else {
        x
    }
}

/// The bits of `x` without its dropped ones: what a mask XORs with, so that
/// a masked kept value keeps its low bits zero.
pub fn kept_bits(x: f64) -> u64 {
    x.to_bits() & !LOW
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_is_to_nearest_and_clears_the_dropped_bits() {
        // The unit in the last kept place of a value in [1, 2) is 2⁻⁴⁰.
        let unit = (2.0f64).powi(-(KEPT_MANTISSA_BITS as i32));
        for x in [1.0, 1.3, -2.7, 1e-300, 6.02e23, -1.0 / 3.0, 0.1] {
            let r = round_to_kept(x);
            assert_eq!(r.to_bits() & LOW, 0, "{x}");
            // Within half a kept unit of x's binade (exact arithmetic: the
            // difference of two nearby f64 is exact).
            let binade = (2.0f64).powi(x.abs().log2().floor() as i32);
            assert!((r - x).abs() <= 0.5 * unit * binade, "{x} → {r}");
            // Idempotent.
            assert_eq!(round_to_kept(r).to_bits(), r.to_bits());
        }
        // Just below a power of two rounds up into the next binade.
        let below_two = f64::from_bits(2.0f64.to_bits() - 1);
        assert_eq!(round_to_kept(below_two), 2.0);
        assert_eq!(round_to_kept(0.0).to_bits(), 0);
        assert_eq!(round_to_kept(-0.0).to_bits(), (-0.0f64).to_bits());
        assert!(round_to_kept(f64::NAN).is_nan());
        assert_eq!(round_to_kept(f64::INFINITY), f64::INFINITY);
        // The largest finite value would carry into infinity: left as it is.
        assert_eq!(round_to_kept(f64::MAX), f64::MAX);
    }

    #[test]
    fn masks_with_kept_bits_keep_the_low_bits_zero() {
        let (a, m) = (round_to_kept(1.234_567), 1.234_568_9);
        let masked = a.to_bits() ^ kept_bits(m);
        assert_eq!(masked & LOW, 0);
        assert_eq!(f64::from_bits(masked ^ kept_bits(m)), a);
    }
}
