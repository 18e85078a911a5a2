//! The test's script: the `MOCK_XR_*` environment variables (see the crate
//! notes), read when the instance is created or when a call needs them.

use crate::state::State;

/// Reads the variables that shape an instance into a fresh state: the API
/// version accepted, the frame after which the session is lost, the frame at
/// which help is pressed, and whether a STAGE space is offered.
pub(crate) fn configure(s: &mut State) {
    s.max_minor = match std::env::var("MOCK_XR_API").as_deref() {
        Ok("1.1") => 1,
        _ => 0,
    };
    s.loss_after = env_u64("MOCK_XR_LOSS_AFTER");
    s.help_at = env_u64("MOCK_XR_HELP_AT");
    s.no_stage = std::env::var_os("MOCK_XR_NO_STAGE").is_some();
}

/// `MOCK_XR_WALK=x,y`: where both thumbsticks are held (default: centred).
pub(crate) fn walk() -> (f32, f32) {
    std::env::var("MOCK_XR_WALK")
        .ok()
        .and_then(|v| {
            let (a, b) = v.split_once(',')?;
            Some((a.parse().ok()?, b.parse().ok()?))
        })
        .unwrap_or((0.0, 0.0))
}

/// `MOCK_XR_REPORT`: where the JSON report goes.
pub(crate) fn report_path() -> Option<String> {
    std::env::var("MOCK_XR_REPORT").ok()
}

/// `MOCK_XR_CAPTURE`: where the last projection frame's image goes.
pub(crate) fn capture_path() -> Option<String> {
    std::env::var("MOCK_XR_CAPTURE").ok()
}

fn env_u64(name: &str) -> Option<u64> {
    std::env::var(name).ok().and_then(|v| v.parse().ok())
}
