//! The ground station's side of the switches: what it asked for, merged with the radio's.
//!
//! The supervisor decides on three switches, arm, manual and kill. Without a ground station
//! they are the radio's. With one, arm and manual become latches that both can move: a radio
//! switch acts when it is flipped (so a radio left in one position does not undo a ground
//! command every step), a ground command when it is accepted. The radio keeps priority:
//!
//! - kill: the radio's kill switch and the ground's terminate each stop the motors on their
//!   own; neither can release the other (a terminate is released only by a ground disarm, and
//!   not while the radio's kill switch is on);
//! - manual: while the radio's manual switch is on, its sticks fly and the ground's mode
//!   commands are refused; flipping it on takes over from a ground manual flight;
//! - arm: flipping the radio's arm switch off lands, whatever the ground asked.
//!
//! Without ground messages the latches follow the radio's switches exactly, so the flight is
//! the one the radio alone would fly.

use crate::msgs::{GroundMessages, GroundSticks, PilotInput};

/// Link supervision and the bounds of ground commands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundLinkConfig {
    /// A ground station heard once and then silent for this long (s) raises "link lost" and
    /// the vehicle holds. Three missed heartbeats of a ground station sending them at 1 Hz.
    pub link_timeout_s: f32,
    /// After "link lost", hold this much longer (s), then land, unless the link returns.
    pub link_lost_land_s: f32,
    /// A manual takeover from the ground needs sticks newer than this (s); sticks that stop
    /// for this long end it (as a lost link).
    pub sticks_timeout_s: f32,
    /// Bounds (m above the take-off floor) of a take-off height a ground station may ask for.
    pub min_takeoff_height_m: f32,
    pub max_takeoff_height_m: f32,
}

impl Default for GroundLinkConfig {
    fn default() -> Self {
        Self {
            link_timeout_s: 3.0,
            link_lost_land_s: 10.0,
            sticks_timeout_s: 0.5,
            min_takeoff_height_m: 0.3,
            max_takeoff_height_m: 3.0,
        }
    }
}

/// The latched switches, the terminate latch, the heartbeat clock and the ground's sticks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GroundLink {
    pub config: GroundLinkConfig,
    /// The radio's arm and manual switches last step, to see them flipped.
    radio_arm: bool,
    radio_manual: bool,
    radio_kill: bool,
    arm: bool,
    manual: bool,
    /// SAFETY-CRITICAL: a ground terminate holds the motors off until a ground disarm.
    terminated: bool,
    /// When the last ground heartbeat arrived; `None` until one has been heard.
    heartbeat_t_s: Option<f64>,
    sticks: Option<(f64, GroundSticks)>,
}

impl GroundLink {
    pub fn new(config: GroundLinkConfig) -> Self {
        Self {
            config,
            ..Self::default()
        }
    }

    /// Takes this step's radio switches (a flipped one moves its latch) and heartbeat.
    pub fn observe(&mut self, t_s: f64, radio: &PilotInput, ground: &GroundMessages) {
        if radio.arm != self.radio_arm {
            self.arm = radio.arm;
        }
        if radio.manual != self.radio_manual {
            self.manual = radio.manual;
        }
        self.radio_arm = radio.arm;
        self.radio_manual = radio.manual;
        self.radio_kill = radio.kill;
        if ground.heartbeat {
            self.heartbeat_t_s = Some(t_s);
        }
    }

    /// The switches and sticks the supervisor and the manual mode act on.
    pub fn switches(&self, radio: &PilotInput) -> PilotInput {
        let mut p = *radio;
        p.arm = self.arm;
        p.manual = self.manual;
        // SAFETY-CRITICAL: either kill stops the motors.
        p.kill = radio.kill || self.terminated;
        if let (true, Some((_, s))) = (self.ground_manual(), self.sticks) {
            p.roll_norm = s.roll_norm;
            p.pitch_norm = s.pitch_norm;
            p.yaw_norm = s.yaw_norm;
            p.throttle_norm = s.throttle_norm;
        }
        p
    }

    /// Manual flight on the ground station's sticks (the radio's manual switch is off).
    pub fn ground_manual(&self) -> bool {
        self.manual && !self.radio_manual
    }

    pub fn radio_manual(&self) -> bool {
        self.radio_manual
    }

    pub fn radio_kill(&self) -> bool {
        self.radio_kill
    }

    pub fn terminated(&self) -> bool {
        self.terminated
    }

    /// SAFETY-CRITICAL: latches the ground's kill.
    pub fn terminate(&mut self) {
        self.terminated = true;
    }

    /// Releases the terminate latch and the arm latch (a ground disarm); the manual latch goes
    /// back to the radio's switch, which the next arming by radio obeys.
    pub fn disarm(&mut self) {
        self.terminated = false;
        self.arm = false;
        self.manual = self.radio_manual;
    }

    pub fn follow_radio_arm(&mut self) {
        self.arm = self.radio_arm;
    }

    pub fn set_arm(&mut self, arm: bool) {
        self.arm = arm;
    }

    pub fn set_manual(&mut self, manual: bool) {
        self.manual = manual;
    }

    /// Keeps sticks that are finite and within their ranges; false (and nothing kept) otherwise.
    pub fn take_sticks(&mut self, t_s: f64, s: GroundSticks) -> bool {
        let centred = [s.roll_norm, s.pitch_norm, s.yaw_norm];
        let ok = centred.iter().all(|v| (-1.0..=1.0).contains(v))
            && (0.0..=1.0).contains(&s.throttle_norm);
        if ok {
            self.sticks = Some((t_s, s));
        }
        ok
    }

    /// Ground sticks have arrived within `sticks_timeout_s`.
    pub fn sticks_fresh(&self, t_s: f64) -> bool {
        self.sticks
            .is_some_and(|(at, _)| ((t_s - at) as f32) <= self.config.sticks_timeout_s)
    }

    /// How long (s) the link has been lost: past `link_timeout_s` without a heartbeat after
    /// one was heard. `None` while it is alive or was never heard.
    pub fn lost_for_s(&self, t_s: f64) -> Option<f32> {
        let silent_s = (t_s - self.heartbeat_t_s?) as f32;
        (silent_s > self.config.link_timeout_s).then_some(silent_s - self.config.link_timeout_s)
    }

    /// Forgets a ground station that has gone (on the ground, disarmed): a later flight by
    /// radio alone is not landed for its absence.
    pub fn forget_if_lost(&mut self, t_s: f64) {
        if self.lost_for_s(t_s).is_some() {
            self.heartbeat_t_s = None;
        }
    }
}
