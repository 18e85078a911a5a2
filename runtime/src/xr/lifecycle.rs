//! The OpenXR session lifecycle as a pure state machine: events in, actions out.
//!
//! OpenXR tells an application where its session stands only through
//! `XrEventDataSessionStateChanged` events (OpenXR 1.0 spec, §9.3 "Session
//! Lifecycle"); the application must answer some of them with calls:
//!
//! | state          | the application                                            |
//! |----------------|------------------------------------------------------------|
//! | IDLE           | waits (the session exists but is not running)              |
//! | READY          | calls `xrBeginSession`, then runs the frame loop           |
//! | SYNCHRONIZED   | keeps the frame loop going; frames are not shown           |
//! | VISIBLE        | renders; frames are shown, input goes elsewhere            |
//! | FOCUSED        | renders and reads input                                    |
//! | STOPPING       | calls `xrEndSession`; the frame loop stops                 |
//! | LOSS_PENDING   | destroys the session; may try to create a new one          |
//! | EXITING        | destroys the session and leaves                            |
//!
//! An application that wants to stop while the session runs calls
//! `xrRequestExitSession` and keeps the frame loop going until the runtime
//! answers with STOPPING (then IDLE, then EXITING). `XrEventDataInstanceLossPending`
//! means the whole runtime is going away: everything is destroyed.
//!
//! [`Lifecycle`] makes those decisions without touching OpenXR, so they are
//! unit-tested against scripted event sequences; `xr::session` feeds it the
//! polled events and carries out the [`Action`]s it returns, in order.

/// `XrSessionState`, without the runtime's numbering.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum XrState {
    Unknown,
    Idle,
    Ready,
    Synchronized,
    Visible,
    Focused,
    Stopping,
    LossPending,
    Exiting,
}

/// What happens to the session.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// `XrEventDataSessionStateChanged`.
    StateChanged(XrState),
    /// `XrEventDataInstanceLossPending`: the runtime is going away.
    InstanceLossPending,
    /// The user (Ctrl-C, or `--frames` reached) wants to stop.
    ExitRequested,
    /// A new session was created after a loss; it starts in IDLE.
    SessionRecreated,
    /// Creating a new session after a loss failed (the runtime or headset is
    /// not back yet).
    RecreateFailed,
}

/// Why the loop ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExitReason {
    /// The application asked (and the runtime agreed, where a session ran).
    Requested,
    /// The runtime ended the session on its own (EXITING without a request:
    /// the user quit from the runtime's menu).
    RuntimeExiting,
    /// `XrEventDataInstanceLossPending`.
    InstanceLost,
    /// The session was lost and could not be created again.
    SessionLost,
}

/// What the caller must do, in the order given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// `xrBeginSession` with the primary stereo view configuration; the frame
    /// loop (wait, begin, end frame) starts.
    BeginSession,
    /// `xrEndSession`; the frame loop stops.
    EndSession,
    /// `xrRequestExitSession`; keep the frame loop going until STOPPING.
    RequestExit,
    /// Frames carry rendered layers from now on (VISIBLE or FOCUSED).
    StartRendering,
    /// Frames are submitted without layers from now on.
    StopRendering,
    /// Destroy the session and everything made from it (swapchains, spaces).
    DestroySession,
    /// Create a new session on the same instance and Vulkan device; report
    /// [`Event::SessionRecreated`] or [`Event::RecreateFailed`].
    RecreateSession,
    /// Leave the loop; everything left is torn down.
    Exit(ExitReason),
}

/// How many times a lost session is created again before giving up. A runtime
/// that restarts (a headset re-plugged, a compositor crash) is back within a
/// few attempts; the caller waits about a second between them.
pub const MAX_RECREATE_ATTEMPTS: u32 = 10;

/// The session lifecycle's state.
#[derive(Clone, Debug)]
pub struct Lifecycle {
    state: XrState,
    /// A session handle exists (created, not yet destroyed).
    session_exists: bool,
    /// Between `xrBeginSession` and `xrEndSession`: the frame loop runs.
    running: bool,
    /// Frames carry layers (VISIBLE or FOCUSED, and no exit requested).
    rendering: bool,
    exit_requested: bool,
    exit: Option<ExitReason>,
    recreate_attempts: u32,
    max_recreate_attempts: u32,
}

impl Default for Lifecycle {
    fn default() -> Self {
        Lifecycle::new(MAX_RECREATE_ATTEMPTS)
    }
}

impl Lifecycle {
    /// The state right after `xrCreateSession` succeeded (the runtime is about
    /// to report IDLE, then READY).
    pub fn new(max_recreate_attempts: u32) -> Lifecycle {
        Lifecycle {
            state: XrState::Unknown,
            session_exists: true,
            running: false,
            rendering: false,
            exit_requested: false,
            exit: None,
            recreate_attempts: 0,
            max_recreate_attempts,
        }
    }

    /// The last state the runtime reported.
    pub fn state(&self) -> XrState {
        self.state
    }

    /// Whether the frame loop (wait, begin, end frame) must run.
    pub fn is_running(&self) -> bool {
        self.running
    }

    /// Whether frames should carry rendered layers.
    pub fn should_render(&self) -> bool {
        self.rendering
    }

    /// Whether the session has input focus (actions are only active then).
    pub fn input_focused(&self) -> bool {
        self.running && self.state == XrState::Focused
    }

    /// Whether a session handle exists.
    pub fn session_exists(&self) -> bool {
        self.session_exists
    }

    /// Whether an exit was asked for.
    pub fn exit_requested(&self) -> bool {
        self.exit_requested
    }

    /// Why the loop ended, once it has.
    pub fn exit_reason(&self) -> Option<ExitReason> {
        self.exit
    }

    pub fn is_done(&self) -> bool {
        self.exit.is_some()
    }

    /// Feeds one event; returns what to do, in order.
    pub fn handle(&mut self, event: Event) -> Vec<Action> {
        let mut actions = Vec::new();
        if self.exit.is_some() {
            return actions;
        }
        match event {
            Event::StateChanged(state) => {
                self.state = state;
                self.on_state(state, &mut actions);
            }
            Event::InstanceLossPending => {
                self.stop_rendering(&mut actions);
                // With the instance going away, xrEndSession would fail; the
                // session is only destroyed.
                self.running = false;
                if self.session_exists {
                    self.session_exists = false;
                    actions.push(Action::DestroySession);
                }
                self.finish(ExitReason::InstanceLost, &mut actions);
            }
            Event::ExitRequested => {
                if self.exit_requested {
                    return actions;
                }
                self.exit_requested = true;
                self.stop_rendering(&mut actions);
                if self.running {
                    // The runtime answers with STOPPING, IDLE, EXITING.
                    actions.push(Action::RequestExit);
                } else {
                    // Not running (IDLE before READY, or waiting to recreate a
                    // lost session): nothing to wind down with the runtime.
                    if self.session_exists {
                        self.session_exists = false;
                        actions.push(Action::DestroySession);
                    }
                    self.finish(ExitReason::Requested, &mut actions);
                }
            }
            Event::SessionRecreated => {
                self.session_exists = true;
                self.state = XrState::Unknown;
                self.recreate_attempts = 0;
            }
            Event::RecreateFailed => self.try_recreate(&mut actions),
        }
        actions
    }

    fn on_state(&mut self, state: XrState, actions: &mut Vec<Action>) {
        match state {
            XrState::Ready => {
                if !self.running {
                    self.running = true;
                    actions.push(Action::BeginSession);
                    if self.exit_requested {
                        // Cannot happen through `handle` (a request while not
                        // running ends at once), kept for robustness.
                        actions.push(Action::RequestExit);
                    }
                }
            }
            XrState::Synchronized | XrState::Idle | XrState::Unknown => {
                self.stop_rendering(actions);
            }
            XrState::Visible | XrState::Focused => {
                if self.running && !self.rendering && !self.exit_requested {
                    self.rendering = true;
                    actions.push(Action::StartRendering);
                }
            }
            XrState::Stopping => {
                self.stop_rendering(actions);
                if self.running {
                    self.running = false;
                    actions.push(Action::EndSession);
                }
            }
            XrState::Exiting => {
                self.stop_rendering(actions);
                // EXITING follows IDLE, so the session is no longer running;
                // xrEndSession is not valid here.
                self.running = false;
                if self.session_exists {
                    self.session_exists = false;
                    actions.push(Action::DestroySession);
                }
                let reason = if self.exit_requested {
                    ExitReason::Requested
                } else {
                    ExitReason::RuntimeExiting
                };
                self.finish(reason, actions);
            }
            XrState::LossPending => {
                self.stop_rendering(actions);
                // A losing session is destroyed without xrEndSession.
                self.running = false;
                if self.session_exists {
                    self.session_exists = false;
                    actions.push(Action::DestroySession);
                }
                if self.exit_requested {
                    self.finish(ExitReason::Requested, actions);
                } else {
                    self.try_recreate(actions);
                }
            }
        }
    }

    fn try_recreate(&mut self, actions: &mut Vec<Action>) {
        if self.exit_requested {
            self.finish(ExitReason::Requested, actions);
        } else if self.recreate_attempts >= self.max_recreate_attempts {
            self.finish(ExitReason::SessionLost, actions);
        } else {
            self.recreate_attempts += 1;
            actions.push(Action::RecreateSession);
        }
    }

    fn stop_rendering(&mut self, actions: &mut Vec<Action>) {
        if self.rendering {
            self.rendering = false;
            actions.push(Action::StopRendering);
        }
    }

    fn finish(&mut self, reason: ExitReason, actions: &mut Vec<Action>) {
        self.exit = Some(reason);
        actions.push(Action::Exit(reason));
    }
}

#[cfg(test)]
mod tests {
    use super::Action::*;
    use super::Event::*;
    use super::XrState::*;
    use super::*;

    /// Feeds `events` and returns every action, in order.
    fn run(machine: &mut Lifecycle, events: &[Event]) -> Vec<Action> {
        events.iter().flat_map(|&e| machine.handle(e)).collect()
    }

    fn states(list: &[XrState]) -> Vec<Event> {
        list.iter().map(|&s| StateChanged(s)).collect()
    }

    #[test]
    fn start_up_to_focus_begins_once_and_renders_once() {
        let mut m = Lifecycle::default();
        let actions = run(
            &mut m,
            &states(&[Idle, Ready, Synchronized, Visible, Focused]),
        );
        assert_eq!(actions, vec![BeginSession, StartRendering]);
        assert!(m.is_running() && m.should_render() && m.input_focused());
        // Losing focus keeps rendering but drops input; losing visibility stops
        // rendering while the frame loop goes on.
        assert!(run(&mut m, &states(&[Visible])).is_empty());
        assert!(m.should_render() && !m.input_focused());
        assert_eq!(run(&mut m, &states(&[Synchronized])), vec![StopRendering]);
        assert!(m.is_running() && !m.should_render());
        assert_eq!(run(&mut m, &states(&[Visible])), vec![StartRendering]);
    }

    #[test]
    fn requested_exit_winds_down_through_stopping_and_exiting() {
        let mut m = Lifecycle::default();
        run(
            &mut m,
            &states(&[Idle, Ready, Synchronized, Visible, Focused]),
        );
        assert_eq!(
            run(&mut m, &[ExitRequested]),
            vec![StopRendering, RequestExit]
        );
        // The frame loop keeps running (without layers) until STOPPING.
        assert!(m.is_running() && !m.should_render() && !m.is_done());
        // A second request changes nothing.
        assert!(run(&mut m, &[ExitRequested]).is_empty());
        // The runtime walks back down; VISIBLE must not restart rendering.
        let actions = run(&mut m, &states(&[Visible, Synchronized, Stopping]));
        assert_eq!(actions, vec![EndSession]);
        assert!(!m.is_running());
        let actions = run(&mut m, &states(&[Idle, Exiting]));
        assert_eq!(actions, vec![DestroySession, Exit(ExitReason::Requested)]);
        assert!(m.is_done() && !m.session_exists());
        // Nothing happens after the end.
        assert!(run(&mut m, &states(&[Ready])).is_empty());
    }

    #[test]
    fn runtime_initiated_exit_is_reported_as_such() {
        let mut m = Lifecycle::default();
        let actions = run(
            &mut m,
            &states(&[
                Idle,
                Ready,
                Synchronized,
                Visible,
                Focused,
                Visible,
                Synchronized,
                Stopping,
                Idle,
                Exiting,
            ]),
        );
        assert_eq!(
            actions,
            vec![
                BeginSession,
                StartRendering,
                StopRendering,
                EndSession,
                DestroySession,
                Exit(ExitReason::RuntimeExiting)
            ]
        );
    }

    #[test]
    fn runtime_may_stop_and_restart_a_session() {
        // STOPPING then READY again without EXITING (e.g. the headset was taken
        // off and put back on): end, then begin again.
        let mut m = Lifecycle::default();
        let actions = run(
            &mut m,
            &states(&[
                Idle,
                Ready,
                Synchronized,
                Stopping,
                Idle,
                Ready,
                Synchronized,
                Visible,
            ]),
        );
        assert_eq!(
            actions,
            vec![BeginSession, EndSession, BeginSession, StartRendering]
        );
        assert!(m.is_running() && m.should_render());
    }

    #[test]
    fn exit_before_ready_destroys_without_ending() {
        let mut m = Lifecycle::default();
        run(&mut m, &states(&[Idle]));
        assert_eq!(
            run(&mut m, &[ExitRequested]),
            vec![DestroySession, Exit(ExitReason::Requested)]
        );
        assert!(m.is_done() && !m.is_running());
    }

    #[test]
    fn loss_pending_destroys_and_recreates_then_resumes() {
        let mut m = Lifecycle::default();
        run(
            &mut m,
            &states(&[Idle, Ready, Synchronized, Visible, Focused]),
        );
        let actions = run(&mut m, &states(&[LossPending]));
        // No xrEndSession for a losing session.
        assert_eq!(
            actions,
            vec![StopRendering, DestroySession, RecreateSession]
        );
        assert!(!m.is_running() && !m.session_exists() && !m.is_done());
        // The runtime is not back yet: retry.
        assert_eq!(run(&mut m, &[RecreateFailed]), vec![RecreateSession]);
        // Back: the new session goes through the start-up again.
        assert!(run(&mut m, &[SessionRecreated]).is_empty());
        assert!(m.session_exists());
        let actions = run(&mut m, &states(&[Idle, Ready, Synchronized, Visible]));
        assert_eq!(actions, vec![BeginSession, StartRendering]);
    }

    #[test]
    fn loss_pending_gives_up_after_the_attempt_limit() {
        let mut m = Lifecycle::new(2);
        run(&mut m, &states(&[Idle, Ready]));
        assert_eq!(
            run(&mut m, &states(&[LossPending])),
            vec![DestroySession, RecreateSession]
        );
        assert_eq!(run(&mut m, &[RecreateFailed]), vec![RecreateSession]);
        assert_eq!(
            run(&mut m, &[RecreateFailed]),
            vec![Exit(ExitReason::SessionLost)]
        );
        assert_eq!(m.exit_reason(), Some(ExitReason::SessionLost));
    }

    #[test]
    fn exit_requested_while_waiting_to_recreate_ends_at_once() {
        let mut m = Lifecycle::default();
        run(&mut m, &states(&[Idle, Ready, LossPending]));
        assert_eq!(
            run(&mut m, &[ExitRequested]),
            vec![Exit(ExitReason::Requested)]
        );
        // A retry result arriving late is ignored.
        assert!(run(&mut m, &[RecreateFailed]).is_empty());
    }

    #[test]
    fn loss_pending_after_an_exit_request_does_not_recreate() {
        let mut m = Lifecycle::default();
        run(&mut m, &states(&[Idle, Ready, Synchronized, Visible]));
        run(&mut m, &[ExitRequested]);
        assert_eq!(
            run(&mut m, &states(&[LossPending])),
            vec![DestroySession, Exit(ExitReason::Requested)]
        );
    }

    #[test]
    fn instance_loss_destroys_everything_and_exits() {
        let mut m = Lifecycle::default();
        run(
            &mut m,
            &states(&[Idle, Ready, Synchronized, Visible, Focused]),
        );
        assert_eq!(
            run(&mut m, &[InstanceLossPending]),
            vec![
                StopRendering,
                DestroySession,
                Exit(ExitReason::InstanceLost)
            ]
        );
        assert!(!m.is_running() && m.is_done());
        // Instance loss while waiting to recreate: nothing left to destroy.
        let mut m = Lifecycle::default();
        run(&mut m, &states(&[Idle, LossPending]));
        assert_eq!(
            run(&mut m, &[InstanceLossPending]),
            vec![Exit(ExitReason::InstanceLost)]
        );
    }

    #[test]
    fn visible_before_ready_does_not_render() {
        // A misbehaving runtime that skips READY must not make the application
        // render outside a running session.
        let mut m = Lifecycle::default();
        assert!(run(&mut m, &states(&[Idle, Visible, Focused])).is_empty());
        assert!(!m.should_render() && !m.input_focused());
    }
}
