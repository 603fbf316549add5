//! What each ground command does in each mode, and the answer the link acknowledges with.
//!
//! A command that changes the mode does so in the step that receives it. Refusals say why
//! ([`Refusal`]); nothing refused changes anything. Summary:
//!
//! - Terminate: always taken; the motors stop in this step and stay off (latched) until a
//!   ground disarm with the radio's kill switch off.
//! - Arm: from disarmed, arms as the radio's arm switch does (take-off to the configured hold
//!   height, or manual when the radio's manual switch is on); needs a trustworthy estimate and
//!   a battery that is not critical. Armed already: accepted, nothing changes. Refused while
//!   landing (the landing finishes first) and while killed.
//! - Takeoff: from disarmed, arms and climbs to the asked height (bounded by
//!   `GroundLinkConfig`); in take-off or hold, moves the hold height there.
//! - Disarm: on the floor (below the touchdown height, slower than the touchdown speed) stops
//!   the motors; in the air it is refused: land instead. In "killed" it releases the latch.
//! - Land: from any flying mode; from a manual flight only when the ground flies it.
//! - Return and SetMode(Explore): need a companion computer that is talking (it flies them).
//! - SetMode(Hold): from exploring, returning or a ground manual flight: hold where it is.
//! - SetMode(Manual): takeover with the ground's sticks, which must have arrived recently.
//! - Sticks: kept for a ground manual flight when finite and in range.
//!
//! The radio's switches keep priority (see [`super::super::ground`]): with its manual switch on,
//! mode commands are refused with [`Refusal::RadioInCharge`].

use super::{Status, Supervisor};
use crate::msgs::{CommandResult, FlightMode, GroundAck, GroundCommand, GroundMode, Refusal};

use CommandResult::{Accepted, InvalidParameter, Refused};
use FlightMode::{Disarmed, Explore, Hold, Killed, Land, Manual, Return, Takeoff};

impl Supervisor {
    /// The commands the kill logic takes before anything else: terminate, and the disarm that
    /// releases it. `None` for every other command.
    pub(super) fn kill_command(&mut self, c: GroundCommand) -> Option<GroundAck> {
        let result = match c {
            // SAFETY-CRITICAL: the remote kill switch, whatever the mode.
            GroundCommand::Terminate => {
                self.link.terminate();
                Accepted
            }
            GroundCommand::Disarm if self.mode == Killed => {
                if self.link.radio_kill() {
                    Refused(Refusal::RadioInCharge)
                } else {
                    self.link.disarm();
                    Accepted
                }
            }
            _ => return None,
        };
        Some(GroundAck { command: c, result })
    }

    /// Answers a command that arrived while killed, unless it was answered already.
    pub(super) fn refuse_unanswered(&mut self, c: Option<GroundCommand>, why: Refusal) {
        if let (None, Some(command)) = (self.ack, c) {
            self.ack = Some(GroundAck {
                command,
                result: Refused(why),
            });
        }
    }

    /// Carries out one command outside "killed"; may change the mode.
    pub(super) fn command(&mut self, c: GroundCommand, s: &Status) -> CommandResult {
        let flying = matches!(self.mode, Takeoff | Hold | Explore | Return | Land | Manual);
        let radio_manual = self.link.radio_manual();
        match c {
            GroundCommand::Terminate => Accepted,
            GroundCommand::Sticks(sticks) => {
                if self.link.take_sticks(s.t_s, sticks) {
                    Accepted
                } else {
                    InvalidParameter
                }
            }
            GroundCommand::Arm => match self.mode {
                Disarmed => self.arm(s, None),
                Land | Killed => Refused(Refusal::WrongMode),
                _ => Accepted,
            },
            GroundCommand::Takeoff { height_m } => {
                let c = &self.link.config;
                let bounds = c.min_takeoff_height_m..=c.max_takeoff_height_m;
                let height_m = match height_m {
                    None => self.config.takeoff_height_m,
                    // A NaN is in no range.
                    Some(h) if bounds.contains(&h) => h,
                    Some(_) => return InvalidParameter,
                };
                match self.mode {
                    Disarmed if radio_manual => Refused(Refusal::RadioInCharge),
                    Disarmed => self.arm(s, Some(height_m)),
                    Takeoff | Hold => {
                        self.hold_height_m = height_m;
                        Accepted
                    }
                    _ => Refused(Refusal::WrongMode),
                }
            }
            GroundCommand::Disarm => {
                let e = &s.estimate;
                let on_floor = e.position_m[2] < self.config.touchdown_height_m
                    && libm::fabsf(e.velocity_m_s[2]) < self.config.touchdown_speed_m_s;
                if flying && !on_floor {
                    return Refused(Refusal::Airborne);
                }
                self.link.disarm();
                self.set_mode(s.t_s, Disarmed);
                Accepted
            }
            GroundCommand::Land => match self.mode {
                Manual if radio_manual => Refused(Refusal::RadioInCharge),
                _ if flying => {
                    self.link.set_manual(false);
                    self.set_mode(s.t_s, Land);
                    Accepted
                }
                _ => Refused(Refusal::WrongMode),
            },
            GroundCommand::Return => self.mission_mode(Return, s),
            GroundCommand::SetMode(GroundMode::Explore) => self.mission_mode(Explore, s),
            GroundCommand::SetMode(GroundMode::Hold) => match self.mode {
                Hold => Accepted,
                Manual if radio_manual => Refused(Refusal::RadioInCharge),
                Manual if !s.estimate.valid => Refused(Refusal::EstimateInvalid),
                Explore | Return | Manual => {
                    self.link.set_manual(false);
                    self.set_mode(s.t_s, Hold);
                    Accepted
                }
                _ => Refused(Refusal::WrongMode),
            },
            GroundCommand::SetMode(GroundMode::Manual) => match self.mode {
                Manual => Accepted,
                _ if !flying => Refused(Refusal::WrongMode),
                _ if !self.link.sticks_fresh(s.t_s) => Refused(Refusal::NoSticks),
                _ => {
                    self.link.set_manual(true);
                    self.link.set_arm(true);
                    self.set_mode(s.t_s, Manual);
                    Accepted
                }
            },
        }
    }

    /// Arms from disarmed when the radio's arm switch would: the arming happens in this step.
    fn arm(&mut self, s: &Status, height_m: Option<f32>) -> CommandResult {
        if self.battery_critical {
            return Refused(Refusal::BatteryCritical);
        }
        if !self.link.radio_manual() && !s.estimate.valid {
            return Refused(Refusal::EstimateInvalid);
        }
        self.link.set_arm(true);
        // The command is the deliberate act the off-to-on edge of the radio's switch stands for.
        self.arm_seen_off = true;
        self.takeoff_height_request_m = height_m;
        Accepted
    }

    /// Exploring and returning, which follow the companion's setpoints, from the hold or from
    /// each other.
    fn mission_mode(&mut self, to: FlightMode, s: &Status) -> CommandResult {
        if self.mode == to {
            return Accepted;
        }
        if !matches!(self.mode, Hold | Explore) {
            return Refused(Refusal::WrongMode);
        }
        if !s.mission.companion_present {
            return Refused(Refusal::NoCompanion);
        }
        self.set_mode(s.t_s, to);
        Accepted
    }
}
