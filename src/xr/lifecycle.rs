//! The OpenXR session's life, as a small pure state machine: the runtime reports a state,
//! the machine says what Argile must do (begin, end, save and destroy the session, quit).
//!
//! ```text
//!            ┌──────────────── (loss) ───────────────┐
//!  IDLE ─► READY ─► SYNCHRONIZED ⇄ VISIBLE ⇄ FOCUSED  ▼
//!   ▲  begin ▲           │                        LOSS_PENDING ─► save, destroy, recreate
//!   │        └ xrBeginSession       (instance loss ends every session: `XrStation` owns it)
//!   │                    ▼
//!   └──── end ◄──── STOPPING        IDLE ─► EXITING ─► save, destroy, quit
//! ```
//!
//! Frames run (wait, begin, end) only between `xrBeginSession` and `xrEndSession`; images
//! are drawn only when the runtime says the frame should be rendered (VISIBLE or FOCUSED);
//! input acts only while FOCUSED.

/// A session state as the runtime reports it (`XrSessionState`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SessionState {
    /// Created, not ready to begin.
    Idle,
    /// Ready: the application begins the session.
    Ready,
    /// Frames are synchronised with the display, nothing is shown.
    Synchronized,
    /// The application's frames are shown.
    Visible,
    /// Shown and receiving input.
    Focused,
    /// The runtime asks the application to end the session.
    Stopping,
    /// The session is lost: the application destroys it (and may make a new one).
    LossPending,
    /// The application is to quit.
    Exiting,
}

impl SessionState {
    /// The runtime's name for it (`FOCUSED` ...).
    pub fn name(self) -> &'static str {
        match self {
            SessionState::Idle => "IDLE",
            SessionState::Ready => "READY",
            SessionState::Synchronized => "SYNCHRONIZED",
            SessionState::Visible => "VISIBLE",
            SessionState::Focused => "FOCUSED",
            SessionState::Stopping => "STOPPING",
            SessionState::LossPending => "LOSS_PENDING",
            SessionState::Exiting => "EXITING",
        }
    }
}

/// What Argile must do after a state change or an event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// Nothing.
    Nothing,
    /// Call `xrBeginSession` (primary stereo); frames run from now on.
    Begin,
    /// Call `xrEndSession`; frames stop.
    End,
    /// Save the sculpt and destroy the session; a new one may be created on this instance.
    SaveAndRecreate,
    /// Save the sculpt, destroy everything OpenXR and quit.
    SaveAndQuit,
}

/// The session's state and whether frames run, driven by the runtime's events.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lifecycle {
    state: SessionState,
    /// Between `xrBeginSession` and `xrEndSession`.
    running: bool,
    /// Argile asked to quit (`xrRequestExitSession`).
    exit_requested: bool,
    /// The runtime has reported a state since the session was created.
    reported: bool,
}

impl Default for Lifecycle {
    fn default() -> Self {
        Self::new()
    }
}

impl Lifecycle {
    /// A session just created: IDLE, not running.
    pub fn new() -> Self {
        Self { state: SessionState::Idle, running: false, exit_requested: false, reported: false }
    }

    /// The state last reported.
    pub fn state(&self) -> SessionState {
        self.state
    }

    /// Whether frames run (`xrWaitFrame`, `xrBeginFrame`, `xrEndFrame`).
    pub fn running(&self) -> bool {
        self.running
    }

    /// Whether controllers act on the clay (the session has the input focus).
    pub fn focused(&self) -> bool {
        self.running && self.state == SessionState::Focused
    }

    /// Whether Argile asked to quit.
    pub fn exit_requested(&self) -> bool {
        self.exit_requested
    }

    /// Whether the runtime may go from `from` to `to` (the transitions the specification
    /// allows; any state may be lost).
    pub fn allowed(from: SessionState, to: SessionState) -> bool {
        use SessionState::*;
        matches!(
            (from, to),
            (Idle, Ready)
                | (Ready, Synchronized)
                | (Synchronized, Visible)
                | (Visible, Focused)
                | (Focused, Visible)
                | (Visible, Synchronized)
                | (Synchronized, Stopping)
                | (Stopping, Idle)
                | (Idle, Exiting)
                | (_, LossPending)
        )
    }

    /// The runtime reports `to`: returns what Argile must do, or why the report breaks the
    /// specification's order (the state is taken all the same: the runtime is the judge).
    /// A new session is IDLE without an event; the runtime's first event reports it IDLE
    /// again (the specification's first transition, into IDLE), which is in order.
    pub fn on_state(&mut self, to: SessionState) -> (Command, Option<String>) {
        let first_idle = !self.reported && self.state == SessionState::Idle && to == SessionState::Idle;
        self.reported = true;
        let complaint = (!first_idle && !Self::allowed(self.state, to))
            .then(|| format!("the runtime went from {} to {}", self.state.name(), to.name()));
        self.state = to;
        let command = match to {
            SessionState::Ready if !self.running => {
                self.running = true;
                Command::Begin
            }
            SessionState::Stopping if self.running => {
                self.running = false;
                Command::End
            }
            SessionState::Exiting => Command::SaveAndQuit,
            SessionState::LossPending => {
                self.running = false;
                if self.exit_requested {
                    Command::SaveAndQuit
                } else {
                    Command::SaveAndRecreate
                }
            }
            _ => Command::Nothing,
        };
        (command, complaint)
    }

    /// Argile wants to quit: while frames run, `xrRequestExitSession` (returns true) and the
    /// runtime walks the session down to EXITING; otherwise there is nothing to wait for.
    pub fn request_exit(&mut self) -> bool {
        self.exit_requested = true;
        self.running
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use SessionState::*;

    #[test]
    fn a_session_begins_when_ready_runs_and_ends_when_stopping() {
        let mut l = Lifecycle::new();
        assert!(!l.running());
        // Real runtimes first report the new session IDLE: that is no complaint, a second
        // IDLE is.
        assert_eq!(l.on_state(Idle), (Command::Nothing, None));
        assert_eq!(l.on_state(Idle).1.as_deref(), Some("the runtime went from IDLE to IDLE"));
        let mut l = Lifecycle::new();
        assert_eq!(l.on_state(Ready), (Command::Begin, None));
        assert!(l.running() && !l.focused());
        for s in [Synchronized, Visible, Focused] {
            assert_eq!(l.on_state(s), (Command::Nothing, None));
        }
        assert!(l.focused());
        for s in [Visible, Synchronized] {
            assert_eq!(l.on_state(s).0, Command::Nothing);
            assert!(l.running() && !l.focused());
        }
        assert_eq!(l.on_state(Stopping), (Command::End, None));
        assert!(!l.running());
        assert_eq!(l.on_state(Idle), (Command::Nothing, None));
        // A runtime may make it ready again (the headset put back on).
        assert_eq!(l.on_state(Ready).0, Command::Begin);
    }

    #[test]
    fn asking_to_quit_waits_for_exiting_then_saves() {
        let mut l = Lifecycle::new();
        assert!(!l.request_exit(), "before the session runs there is nothing to wait for");
        let mut l = Lifecycle::new();
        l.on_state(Ready);
        l.on_state(Synchronized);
        assert!(l.request_exit());
        assert!(l.exit_requested());
        assert_eq!(l.on_state(Stopping).0, Command::End);
        assert_eq!(l.on_state(Idle).0, Command::Nothing);
        assert_eq!(l.on_state(Exiting), (Command::SaveAndQuit, None));
    }

    #[test]
    fn loss_saves_and_recreates_unless_quitting() {
        let mut l = Lifecycle::new();
        l.on_state(Ready);
        l.on_state(Synchronized);
        l.on_state(Visible);
        l.on_state(Focused);
        assert_eq!(l.on_state(LossPending), (Command::SaveAndRecreate, None));
        assert!(!l.running());
        let mut l = Lifecycle::new();
        l.on_state(Ready);
        l.request_exit();
        assert_eq!(l.on_state(LossPending).0, Command::SaveAndQuit);
    }

    #[test]
    fn out_of_order_reports_are_named_and_still_followed() {
        let mut l = Lifecycle::new();
        let (command, complaint) = l.on_state(Focused);
        assert_eq!(command, Command::Nothing);
        assert_eq!(complaint.as_deref(), Some("the runtime went from IDLE to FOCUSED"));
        assert_eq!(l.state(), Focused);
        // Every state can be lost; only the listed steps are allowed otherwise.
        let all = [Idle, Ready, Synchronized, Visible, Focused, Stopping, LossPending, Exiting];
        for from in all {
            assert!(Lifecycle::allowed(from, LossPending));
            let onward = all.iter().filter(|&&to| to != LossPending && Lifecycle::allowed(from, to)).count();
            let expected = match from {
                Idle | Visible => 2,
                Synchronized => 2,
                Ready | Focused | Stopping => 1,
                LossPending | Exiting => 0,
            };
            assert_eq!(onward, expected, "{from:?}");
        }
    }
}
