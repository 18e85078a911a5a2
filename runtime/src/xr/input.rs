//! Controller input: one action set with four actions, and suggested bindings
//! for the common controllers.
//!
//! | action     | type     | does                                                  |
//! |------------|----------|-------------------------------------------------------|
//! | `walk`     | vector2  | left stick/trackpad: walk along the head's heading    |
//! | `turn`     | vector2  | right stick/trackpad x: snap turn; y: exposure ±½ stop |
//! | `recentre` | boolean  | right stick click (menu on sticks-less controllers): back to the stored camera (`radview`'s `r`, Remington 1992, app. C.1) |
//! | `help`     | boolean  | left menu button: toggle the help overlay (`radview`'s F1/F2) |
//!
//! Bindings can only be suggested before any action set is attached to a
//! session, so the action set is made once per instance ([`XrInput::new`]) and
//! attached to each session (a lost session's replacement included).

use super::{XrContext, XrError};
use glam::DVec2;
use openxr as xr;

/// The actions, by role.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    Walk,
    Turn,
    Recentre,
    Help,
}

/// Suggested bindings: interaction profile, then (action, input path) pairs.
/// Profiles the runtime does not know are skipped.
pub const BINDINGS: &[(&str, &[(Control, &str)])] = &[
    (
        "/interaction_profiles/oculus/touch_controller",
        &[
            (Control::Walk, "/user/hand/left/input/thumbstick"),
            (Control::Turn, "/user/hand/right/input/thumbstick"),
            (Control::Recentre, "/user/hand/right/input/thumbstick/click"),
            (Control::Help, "/user/hand/left/input/menu/click"),
        ],
    ),
    (
        "/interaction_profiles/valve/index_controller",
        &[
            (Control::Walk, "/user/hand/left/input/thumbstick"),
            (Control::Turn, "/user/hand/right/input/thumbstick"),
            (Control::Recentre, "/user/hand/right/input/thumbstick/click"),
            // The Index controller has no menu button; B is the usual stand-in.
            (Control::Help, "/user/hand/left/input/b/click"),
        ],
    ),
    (
        "/interaction_profiles/microsoft/motion_controller",
        &[
            (Control::Walk, "/user/hand/left/input/thumbstick"),
            (Control::Turn, "/user/hand/right/input/thumbstick"),
            (Control::Recentre, "/user/hand/right/input/thumbstick/click"),
            (Control::Help, "/user/hand/left/input/menu/click"),
        ],
    ),
    (
        "/interaction_profiles/htc/vive_controller",
        &[
            (Control::Walk, "/user/hand/left/input/trackpad"),
            (Control::Turn, "/user/hand/right/input/trackpad"),
            (Control::Recentre, "/user/hand/right/input/menu/click"),
            (Control::Help, "/user/hand/left/input/menu/click"),
        ],
    ),
    (
        // Every runtime supports this one; it has no sticks, so no walking.
        "/interaction_profiles/khr/simple_controller",
        &[
            (Control::Recentre, "/user/hand/right/input/menu/click"),
            (Control::Help, "/user/hand/left/input/menu/click"),
        ],
    ),
];

/// The controls read in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ControlState {
    /// Raw stick deflection (dead zone not yet applied).
    pub walk: DVec2,
    pub turn_x: f64,
    /// The same stick's y: exposure steps ([`super::exposure`]).
    pub turn_y: f64,
    /// True in the frame the button went down.
    pub recentre_pressed: bool,
    pub help_pressed: bool,
}

/// The action set and its actions.
pub struct XrInput {
    walk: xr::Action<xr::Vector2f>,
    turn: xr::Action<xr::Vector2f>,
    recentre: xr::Action<bool>,
    help: xr::Action<bool>,
    set: xr::ActionSet,
}

/// A button state's "went down since the last sync".
fn pressed(state: &xr::ActionState<bool>) -> bool {
    state.is_active && state.changed_since_last_sync && state.current_state
}

fn vector(state: &xr::ActionState<xr::Vector2f>) -> DVec2 {
    if state.is_active {
        DVec2::new(
            f64::from(state.current_state.x),
            f64::from(state.current_state.y),
        )
    } else {
        DVec2::ZERO
    }
}

impl XrInput {
    /// Creates the actions and suggests [`BINDINGS`]; returns the profiles the
    /// runtime refused (it may not know them all).
    pub fn new(instance: &xr::Instance) -> Result<(XrInput, Vec<String>), XrError> {
        let set = instance
            .create_action_set("walkthrough", "Walkthrough", 0)
            .xr("xrCreateActionSet")?;
        let walk = set
            .create_action::<xr::Vector2f>("walk", "Walk", &[])
            .xr("xrCreateAction")?;
        let turn = set
            .create_action::<xr::Vector2f>("turn", "Snap turn", &[])
            .xr("xrCreateAction")?;
        let recentre = set
            .create_action::<bool>("recentre", "Recentre on the stored view", &[])
            .xr("xrCreateAction")?;
        let help = set
            .create_action::<bool>("help", "Show or hide help", &[])
            .xr("xrCreateAction")?;
        let input = XrInput {
            walk,
            turn,
            recentre,
            help,
            set,
        };
        let mut refused = Vec::new();
        for (profile, pairs) in BINDINGS {
            if let Err(e) = input.suggest(instance, profile, pairs) {
                refused.push(format!("{profile} ({e})"));
            }
        }
        Ok((input, refused))
    }

    fn suggest(
        &self,
        instance: &xr::Instance,
        profile: &str,
        pairs: &[(Control, &str)],
    ) -> Result<(), xr::sys::Result> {
        let profile = instance.string_to_path(profile)?;
        let paths = pairs
            .iter()
            .map(|(control, path)| instance.string_to_path(path).map(|p| (*control, p)))
            .collect::<Result<Vec<_>, _>>()?;
        let bindings: Vec<xr::Binding> = paths
            .iter()
            .map(|&(control, path)| match control {
                Control::Walk => xr::Binding::new(&self.walk, path),
                Control::Turn => xr::Binding::new(&self.turn, path),
                Control::Recentre => xr::Binding::new(&self.recentre, path),
                Control::Help => xr::Binding::new(&self.help, path),
            })
            .collect();
        instance.suggest_interaction_profile_bindings(profile, &bindings)
    }

    /// Attaches the action set to a new session.
    pub fn attach<G: xr::Graphics>(&self, session: &xr::Session<G>) -> Result<(), XrError> {
        session
            .attach_action_sets(&[&self.set])
            .xr("xrAttachSessionActionSets")
    }

    /// Syncs the actions and reads them (call once per frame, with focus).
    pub fn read<G: xr::Graphics>(&self, session: &xr::Session<G>) -> Result<ControlState, XrError> {
        session
            .sync_actions(&[xr::ActiveActionSet::new(&self.set)])
            .xr("xrSyncActions")?;
        let null = xr::Path::NULL;
        let walk = self
            .walk
            .state(session, null)
            .xr("xrGetActionStateVector2f")?;
        let turn = self
            .turn
            .state(session, null)
            .xr("xrGetActionStateVector2f")?;
        let recentre = self
            .recentre
            .state(session, null)
            .xr("xrGetActionStateBoolean")?;
        let help = self
            .help
            .state(session, null)
            .xr("xrGetActionStateBoolean")?;
        Ok(ControlState {
            walk: vector(&walk),
            turn_x: vector(&turn).x,
            turn_y: vector(&turn).y,
            recentre_pressed: pressed(&recentre),
            help_pressed: pressed(&help),
        })
    }
}

/// The help text (the headset's counterpart of `radview`'s help window).
pub const HELP: &str = "\
walkthrough controls (OpenXR)
  left stick      walk along your heading
  right stick     snap turn left / right
                  up / down: exposure +/- half a stop
  right stick (click), or right menu
                  recentre: back to the stored camera view
  left menu       show / hide this help
  quit from the runtime's own menu (or --frames N)";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bindings_are_well_formed_and_cover_the_menu() {
        for (profile, pairs) in BINDINGS {
            assert!(profile.starts_with("/interaction_profiles/"), "{profile}");
            assert!(
                pairs.iter().any(|(c, _)| *c == Control::Help),
                "{profile}: no help button"
            );
            for (control, path) in *pairs {
                assert!(path.starts_with("/user/hand/"), "{path}");
                // Vector actions bind to a whole stick or trackpad, buttons to
                // a click component (the runtime rejects type mismatches).
                let is_vector = matches!(control, Control::Walk | Control::Turn);
                let ends_vector = path.ends_with("/thumbstick") || path.ends_with("/trackpad");
                assert_eq!(is_vector, ends_vector, "{profile}: {control:?} {path}");
                if !is_vector {
                    assert!(path.ends_with("/click"), "{path}");
                }
            }
            // No path is bound twice in one profile.
            let mut paths: Vec<&str> = pairs.iter().map(|(_, p)| *p).collect();
            paths.sort_unstable();
            paths.dedup();
            assert_eq!(paths.len(), pairs.len(), "{profile}");
        }
    }
}
