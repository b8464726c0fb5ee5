//! The rules of order the specification sets, apart from any handle or graphics API: the
//! session's state machine, the frame loop's wait/begin/end order and a swapchain's
//! acquire/wait/release order. Each refusal carries the `XrResult` a conformant runtime returns
//! and a sentence saying why.

use openxr_sys as xr;
use std::collections::VecDeque;

/// A refused call: the result and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refusal {
    pub result: xr::Result,
    pub why: String,
}

pub fn refuse<T>(result: xr::Result, why: impl Into<String>) -> Result<T, Refusal> {
    Err(Refusal { result, why: why.into() })
}

pub fn state_name(s: xr::SessionState) -> &'static str {
    match s {
        xr::SessionState::IDLE => "IDLE",
        xr::SessionState::READY => "READY",
        xr::SessionState::SYNCHRONIZED => "SYNCHRONIZED",
        xr::SessionState::VISIBLE => "VISIBLE",
        xr::SessionState::FOCUSED => "FOCUSED",
        xr::SessionState::STOPPING => "STOPPING",
        xr::SessionState::LOSS_PENDING => "LOSS_PENDING",
        xr::SessionState::EXITING => "EXITING",
        _ => "UNKNOWN",
    }
}

/// A session's lifecycle. Every method returns the states entered, in order, which the
/// runtime queues as `XrEventDataSessionStateChanged` events.
#[derive(Debug)]
pub struct Lifecycle {
    state: xr::SessionState,
    running: bool,
    exit_requested: bool,
    focus_wanted: bool,
    lost: bool,
}

impl Lifecycle {
    /// A new session: IDLE, then READY at once (the simulated headset is always worn).
    pub fn new() -> (Lifecycle, Vec<xr::SessionState>) {
        let l = Lifecycle {
            state: xr::SessionState::READY,
            running: false,
            exit_requested: false,
            focus_wanted: true,
            lost: false,
        };
        (l, vec![xr::SessionState::IDLE, xr::SessionState::READY])
    }

    pub fn state(&self) -> xr::SessionState {
        self.state
    }

    pub fn running(&self) -> bool {
        self.running
    }

    pub fn lost(&self) -> bool {
        self.lost
    }

    pub fn focused(&self) -> bool {
        self.state == xr::SessionState::FOCUSED
    }

    /// Whether the application should render the frame (`XrFrameState::shouldRender`).
    pub fn should_render(&self) -> bool {
        matches!(self.state, xr::SessionState::VISIBLE | xr::SessionState::FOCUSED)
    }

    fn go(&mut self, to: &[xr::SessionState]) -> Vec<xr::SessionState> {
        if let Some(&last) = to.last() {
            self.state = last;
        }
        to.to_vec()
    }

    fn check_not_lost(&self) -> Result<(), Refusal> {
        if self.lost {
            return refuse(xr::Result::ERROR_SESSION_LOST, "the session was lost; destroy it");
        }
        Ok(())
    }

    /// `xrBeginSession`.
    pub fn begin(&mut self) -> Result<(), Refusal> {
        self.check_not_lost()?;
        if self.running {
            return refuse(xr::Result::ERROR_SESSION_RUNNING, "the session is already running");
        }
        if self.state != xr::SessionState::READY {
            return refuse(
                xr::Result::ERROR_SESSION_NOT_READY,
                format!("the session is {}, not READY", state_name(self.state)),
            );
        }
        self.running = true;
        Ok(())
    }

    /// `xrEndSession`.
    pub fn end(&mut self) -> Result<Vec<xr::SessionState>, Refusal> {
        self.check_not_lost()?;
        if !self.running {
            return refuse(xr::Result::ERROR_SESSION_NOT_RUNNING, "the session is not running");
        }
        if self.state != xr::SessionState::STOPPING {
            return refuse(
                xr::Result::ERROR_SESSION_NOT_STOPPING,
                format!("the session is {}, not STOPPING", state_name(self.state)),
            );
        }
        self.running = false;
        // Stopping is only ever entered because an exit was asked for (by the application
        // or the script), so the session goes on to EXITING.
        Ok(self.go(&[xr::SessionState::IDLE, xr::SessionState::EXITING]))
    }

    /// Checks that the frame loop may run (`xrWaitFrame`, `xrBeginFrame`, `xrEndFrame`).
    pub fn check_running(&self) -> Result<(), Refusal> {
        self.check_not_lost()?;
        if !self.running {
            return refuse(
                xr::Result::ERROR_SESSION_NOT_RUNNING,
                "the session is not running (xrBeginSession first)",
            );
        }
        Ok(())
    }

    /// After a frame ended: a running READY session becomes SYNCHRONIZED, VISIBLE and, unless
    /// the script took focus away, FOCUSED.
    pub fn frame_ended(&mut self) -> Vec<xr::SessionState> {
        if self.running && !self.lost && self.state == xr::SessionState::READY {
            let mut to = vec![xr::SessionState::SYNCHRONIZED, xr::SessionState::VISIBLE];
            if self.focus_wanted {
                to.push(xr::SessionState::FOCUSED);
            }
            return self.go(&to);
        }
        Vec::new()
    }

    /// `xrRequestExitSession`, or the script's `exit`: down to STOPPING (or, for a session not
    /// yet begun, to IDLE and EXITING).
    pub fn request_exit(&mut self, by_application: bool) -> Result<Vec<xr::SessionState>, Refusal> {
        self.check_not_lost()?;
        if by_application && !self.running {
            return refuse(xr::Result::ERROR_SESSION_NOT_RUNNING, "the session is not running");
        }
        if self.exit_requested || matches!(self.state, xr::SessionState::EXITING) {
            return Ok(Vec::new());
        }
        self.exit_requested = true;
        use xr::SessionState as S;
        Ok(match self.state {
            S::FOCUSED => self.go(&[S::VISIBLE, S::SYNCHRONIZED, S::STOPPING]),
            S::VISIBLE => self.go(&[S::SYNCHRONIZED, S::STOPPING]),
            S::SYNCHRONIZED => self.go(&[S::STOPPING]),
            S::READY if self.running => self.go(&[S::SYNCHRONIZED, S::STOPPING]),
            S::READY | S::IDLE => self.go(&[S::IDLE, S::EXITING]),
            _ => Vec::new(),
        })
    }

    /// The script's `focus_lost` / `focus_gained`.
    pub fn set_focus(&mut self, focus: bool) -> Vec<xr::SessionState> {
        self.focus_wanted = focus;
        match (self.state, focus) {
            (xr::SessionState::FOCUSED, false) if !self.lost => self.go(&[xr::SessionState::VISIBLE]),
            (xr::SessionState::VISIBLE, true) if !self.lost && !self.exit_requested => {
                self.go(&[xr::SessionState::FOCUSED])
            }
            _ => Vec::new(),
        }
    }

    /// The script's `session_loss` (or instance loss): LOSS_PENDING; from then on the session's
    /// calls answer `XR_ERROR_SESSION_LOST`.
    pub fn lose(&mut self) -> Vec<xr::SessionState> {
        if self.lost {
            return Vec::new();
        }
        self.lost = true;
        self.go(&[xr::SessionState::LOSS_PENDING])
    }
}

/// The frame loop's order: `xrWaitFrame`, `xrBeginFrame`, `xrEndFrame`.
#[derive(Debug, Default)]
pub struct FrameLoop {
    waited: u64,
    begun: u64,
    in_frame: bool,
}

impl FrameLoop {
    /// `xrWaitFrame`; returns how many frames were waited for before this one.
    pub fn wait(&mut self) -> Result<u64, Refusal> {
        if self.waited > self.begun {
            // A conformant runtime blocks this call until xrBeginFrame, which a single-threaded
            // application never reaches: refuse instead of hanging the test.
            return refuse(
                xr::Result::ERROR_CALL_ORDER_INVALID,
                "xrWaitFrame called again before xrBeginFrame for the frame already waited for (a runtime would block forever)",
            );
        }
        self.waited += 1;
        Ok(self.waited - 1)
    }

    /// `xrBeginFrame`; returns whether a frame begun before was discarded
    /// (`XR_FRAME_DISCARDED`).
    pub fn begin(&mut self) -> Result<bool, Refusal> {
        if self.waited == self.begun {
            return refuse(
                xr::Result::ERROR_CALL_ORDER_INVALID,
                "xrBeginFrame without a preceding xrWaitFrame",
            );
        }
        self.begun += 1;
        let discarded = self.in_frame;
        self.in_frame = true;
        Ok(discarded)
    }

    /// Whether a frame was begun and not yet ended.
    pub fn in_frame(&self) -> bool {
        self.in_frame
    }

    /// `xrEndFrame`.
    pub fn end(&mut self) -> Result<(), Refusal> {
        if !self.in_frame {
            return refuse(
                xr::Result::ERROR_CALL_ORDER_INVALID,
                "xrEndFrame without a matching xrBeginFrame",
            );
        }
        self.in_frame = false;
        Ok(())
    }
}

/// A swapchain's images through acquire, wait and release.
#[derive(Debug)]
pub struct Ring {
    count: u32,
    next: u32,
    /// Acquired images, oldest first, with whether each was waited for.
    acquired: VecDeque<(u32, bool)>,
    last_released: Option<u32>,
    static_image: bool,
}

impl Ring {
    pub fn new(count: u32, static_image: bool) -> Ring {
        Ring { count, next: 0, acquired: VecDeque::new(), last_released: None, static_image }
    }

    /// `xrAcquireSwapchainImage`.
    pub fn acquire(&mut self) -> Result<u32, Refusal> {
        if self.static_image && (self.last_released.is_some() || !self.acquired.is_empty()) {
            return refuse(
                xr::Result::ERROR_CALL_ORDER_INVALID,
                "a static swapchain's image can be acquired only once",
            );
        }
        if self.acquired.len() as u32 == self.count {
            return refuse(
                xr::Result::ERROR_CALL_ORDER_INVALID,
                format!("all {} images of the swapchain are acquired; release one first", self.count),
            );
        }
        let i = self.next;
        self.next = (self.next + 1) % self.count;
        self.acquired.push_back((i, false));
        Ok(i)
    }

    /// `xrWaitSwapchainImage`: waits for the oldest acquired image not yet waited for.
    pub fn wait(&mut self) -> Result<u32, Refusal> {
        match self.acquired.iter_mut().find(|(_, waited)| !waited) {
            Some((i, waited)) => {
                *waited = true;
                Ok(*i)
            }
            None => refuse(
                xr::Result::ERROR_CALL_ORDER_INVALID,
                "xrWaitSwapchainImage with no acquired image left to wait for",
            ),
        }
    }

    /// `xrReleaseSwapchainImage`: releases the oldest acquired image, which must have been
    /// waited for.
    pub fn release(&mut self) -> Result<u32, Refusal> {
        match self.acquired.front() {
            Some(&(i, true)) => {
                self.acquired.pop_front();
                self.last_released = Some(i);
                Ok(i)
            }
            Some(&(_, false)) => refuse(
                xr::Result::ERROR_CALL_ORDER_INVALID,
                "xrReleaseSwapchainImage before xrWaitSwapchainImage for the oldest acquired image",
            ),
            None => {
                refuse(xr::Result::ERROR_CALL_ORDER_INVALID, "xrReleaseSwapchainImage with no acquired image")
            }
        }
    }

    /// The image a layer shows: the last one released.
    pub fn last_released(&self) -> Option<u32> {
        self.last_released
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use xr::SessionState as S;

    #[test]
    fn a_session_goes_ready_then_focused_after_its_first_frame_then_stops_and_exits() {
        let (mut l, entered) = Lifecycle::new();
        assert_eq!(entered, vec![S::IDLE, S::READY]);
        assert!(!l.should_render());
        assert_eq!(l.end().unwrap_err().result, xr::Result::ERROR_SESSION_NOT_RUNNING);
        l.begin().unwrap();
        assert_eq!(l.begin().unwrap_err().result, xr::Result::ERROR_SESSION_RUNNING);
        assert_eq!(l.frame_ended(), vec![S::SYNCHRONIZED, S::VISIBLE, S::FOCUSED]);
        assert!(l.should_render() && l.focused());
        assert_eq!(l.frame_ended(), vec![]);
        assert_eq!(l.end().unwrap_err().result, xr::Result::ERROR_SESSION_NOT_STOPPING);
        assert_eq!(l.request_exit(false).unwrap(), vec![S::VISIBLE, S::SYNCHRONIZED, S::STOPPING]);
        assert_eq!(l.end().unwrap(), vec![S::IDLE, S::EXITING]);
        assert!(!l.running());
    }

    #[test]
    fn focus_comes_and_goes_and_a_lost_session_refuses_everything() {
        let (mut l, _) = Lifecycle::new();
        l.begin().unwrap();
        assert_eq!(l.set_focus(false), vec![]);
        assert_eq!(l.frame_ended(), vec![S::SYNCHRONIZED, S::VISIBLE]);
        assert_eq!(l.set_focus(true), vec![S::FOCUSED]);
        assert_eq!(l.set_focus(false), vec![S::VISIBLE]);
        assert_eq!(l.lose(), vec![S::LOSS_PENDING]);
        assert_eq!(l.lose(), vec![]);
        assert_eq!(l.check_running().unwrap_err().result, xr::Result::ERROR_SESSION_LOST);
        assert_eq!(l.end().unwrap_err().result, xr::Result::ERROR_SESSION_LOST);
    }

    #[test]
    fn an_exit_before_the_session_begins_goes_straight_to_exiting() {
        let (mut l, _) = Lifecycle::new();
        assert_eq!(l.request_exit(true).unwrap_err().result, xr::Result::ERROR_SESSION_NOT_RUNNING);
        assert_eq!(l.request_exit(false).unwrap(), vec![S::IDLE, S::EXITING]);
        assert_eq!(l.begin().unwrap_err().result, xr::Result::ERROR_SESSION_NOT_READY);
    }

    #[test]
    fn frames_must_be_waited_begun_and_ended_in_order() {
        let mut f = FrameLoop::default();
        assert_eq!(f.begin().unwrap_err().result, xr::Result::ERROR_CALL_ORDER_INVALID);
        assert_eq!(f.end().unwrap_err().result, xr::Result::ERROR_CALL_ORDER_INVALID);
        assert_eq!(f.wait().unwrap(), 0);
        assert_eq!(f.wait().unwrap_err().result, xr::Result::ERROR_CALL_ORDER_INVALID);
        assert!(!f.begin().unwrap());
        // The next frame may be waited for while this one is being rendered.
        assert_eq!(f.wait().unwrap(), 1);
        f.end().unwrap();
        assert!(!f.begin().unwrap());
        assert_eq!(f.wait().unwrap(), 2);
        // Beginning again without ending discards the frame in flight.
        assert!(f.begin().unwrap());
        f.end().unwrap();
        assert_eq!(f.end().unwrap_err().result, xr::Result::ERROR_CALL_ORDER_INVALID);
    }

    #[test]
    fn swapchain_images_are_acquired_waited_and_released_oldest_first() {
        let mut r = Ring::new(2, false);
        assert_eq!(r.wait().unwrap_err().result, xr::Result::ERROR_CALL_ORDER_INVALID);
        assert_eq!(r.release().unwrap_err().result, xr::Result::ERROR_CALL_ORDER_INVALID);
        assert_eq!(r.acquire().unwrap(), 0);
        assert_eq!(r.release().unwrap_err().result, xr::Result::ERROR_CALL_ORDER_INVALID);
        assert_eq!(r.acquire().unwrap(), 1);
        assert_eq!(r.acquire().unwrap_err().result, xr::Result::ERROR_CALL_ORDER_INVALID);
        assert_eq!(r.wait().unwrap(), 0);
        assert_eq!(r.wait().unwrap(), 1);
        assert_eq!(r.wait().unwrap_err().result, xr::Result::ERROR_CALL_ORDER_INVALID);
        assert_eq!(r.release().unwrap(), 0);
        assert_eq!(r.last_released(), Some(0));
        assert_eq!(r.acquire().unwrap(), 0);
        assert_eq!(r.release().unwrap(), 1);
        let mut s = Ring::new(1, true);
        s.acquire().unwrap();
        s.wait().unwrap();
        s.release().unwrap();
        assert_eq!(s.acquire().unwrap_err().result, xr::Result::ERROR_CALL_ORDER_INVALID);
    }
}
