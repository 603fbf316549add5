//! The link: one value per MAVLink connection that turns the vehicle's state into frames and
//! incoming frames into core's plain commands. Bytes in, bytes out: the caller owns the socket
//! or serial port and the clock, and passes the time into every call.

use crate::commands::{ack, ground_command, mav_result, sticks, AckTo};
use crate::counters::DropCounters;
use crate::estimate_in::{estimate_sample, EstimateSample};
use crate::obstacle::obstacle_distance;
use crate::odometry::odometry_from_pose_fix;
use crate::params::{ParamRef, ParamRequest, ParameterStore, RateLimit};
use crate::scanner::{Frame, Scanner};
use crate::signing::{SignatureFault, Signer, SigningKey};
use crate::telemetry::{statustext, SensorRanges, Telemetry, TelemetryInput, TelemetryRates};
use crate::wire::FrameWriter;
use mavlink::dialects::common::{MavMessage, MavSeverity, MavType};
use mavlink::MAVLinkV2MessageRaw;
use plumbline_core::msgs::{CommandResult, GroundCommand, PoseFix};
use plumbline_core::scan::Beam;

/// MAVLink's component id of an autopilot.
pub const COMPONENT_AUTOPILOT: u8 = 1;
/// MAVLink's component id of a companion computer.
pub const COMPONENT_ONBOARD_COMPUTER: u8 = 191;

/// How a link is set up.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkConfig {
    /// This vehicle's MAVLink system id (1 unless several vehicles share a network).
    pub system_id: u8,
    /// This end's component id: [`COMPONENT_AUTOPILOT`] for the vehicle,
    /// [`COMPONENT_ONBOARD_COMPUTER`] for a companion talking to an autopilot.
    pub component_id: u8,
    /// With a key every outgoing frame is signed and state-changing commands are accepted only
    /// when signed with it. Without one nothing is authenticated: say so at start
    /// ([`Link::announce`]).
    pub key: Option<SigningKey>,
    pub rates: TelemetryRates,
    pub ranges: SensorRanges,
    /// PARAM_SET admitted per second on average (a flood beyond is dropped and counted).
    pub param_set_per_s: f64,
    /// PARAM_SET admitted at once after a quiet spell.
    pub param_set_burst: f64,
}

impl Default for LinkConfig {
    fn default() -> Self {
        Self {
            system_id: 1,
            component_id: COMPONENT_AUTOPILOT,
            key: None,
            rates: TelemetryRates::default(),
            ranges: SensorRanges::default(),
            param_set_per_s: 10.0,
            param_set_burst: 20.0,
        }
    }
}

/// The time of a call. `t_s` is the caller's clock (the simulator's time, or seconds since
/// start): message stamps, telemetry rates, the PARAM_SET limit. `unix_s` is wall-clock Unix
/// time, used only for signing timestamps (a peer refuses a new stream more than a minute
/// behind its own clock); it must not go backwards.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkTime {
    pub t_s: f64,
    pub unix_s: f64,
}

impl LinkTime {
    /// A time on a clock that started at Unix time `unix_at_zero_s` and runs at wall speed.
    pub fn since(unix_at_zero_s: f64, t_s: f64) -> Self {
        Self {
            t_s,
            unix_s: unix_at_zero_s + t_s,
        }
    }
}

/// Who sent a request (to address PARAM_ERROR).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Peer {
    pub system_id: u8,
    pub component_id: u8,
}

/// What the ground asked for; refused input never becomes an event (see [`DropCounters`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InboundEvent {
    /// A command for the autopilot. COMMAND_LONG carries `ack`: answer it with
    /// [`Link::acknowledge`] once the autopilot has decided. MANUAL_CONTROL has none.
    Command {
        command: GroundCommand,
        ack: Option<AckTo>,
    },
    /// A ground station's HEARTBEAT (MAV_TYPE_GCS): the ground link is alive.
    GroundHeartbeat { system_id: u8 },
    /// A parameter request: answer with [`Link::serve_param`].
    Param { request: ParamRequest, from: Peer },
    /// On a companion's link (component [`COMPONENT_ONBOARD_COMPUTER`]): its autopilot's own
    /// estimate (ODOMETRY, LOCAL_POSITION_NED or ATTITUDE from component
    /// [`COMPONENT_AUTOPILOT`] of this system), for a [`crate::EstimateWatch`].
    Estimate(EstimateSample),
}

/// One MAVLink connection's state.
#[derive(Clone, Debug)]
pub struct Link {
    writer: FrameWriter,
    signer: Option<Signer>,
    scanner: Scanner,
    telemetry: Telemetry,
    param_limit: RateLimit,
    counters: DropCounters,
    /// Reused to check incoming signatures.
    verify_buf: MAVLinkV2MessageRaw,
}

impl Link {
    pub fn new(config: LinkConfig) -> Self {
        Self {
            writer: FrameWriter::new(config.system_id, config.component_id),
            signer: config.key.map(Signer::new),
            scanner: Scanner::default(),
            telemetry: Telemetry::new(config.rates, config.ranges),
            param_limit: RateLimit::new(config.param_set_per_s, config.param_set_burst),
            counters: DropCounters::default(),
            verify_buf: MAVLinkV2MessageRaw::new(),
        }
    }

    /// True when a key is set: outgoing frames are signed, state changes need signatures.
    pub fn is_signed(&self) -> bool {
        self.signer.is_some()
    }

    /// What the inbound side refused so far, by reason.
    pub fn counters(&self) -> &DropCounters {
        &self.counters
    }

    /// The start-up STATUSTEXT: whether commands are authenticated.
    pub fn announce(&mut self, now: LinkTime, out: &mut Vec<u8>) {
        let (severity, text) = if self.is_signed() {
            (
                MavSeverity::MAV_SEVERITY_INFO,
                "link signed: commands need the key",
            )
        } else {
            (
                MavSeverity::MAV_SEVERITY_WARNING,
                "link unsigned: commands are not authenticated",
            )
        };
        self.send(&statustext(severity, text), now, out);
    }

    /// Appends the telemetry due at `now` (and a STATUSTEXT for each mode change or failsafe).
    pub fn telemetry(&mut self, report: &TelemetryInput<'_>, now: LinkTime, out: &mut Vec<u8>) {
        let Self {
            writer,
            signer,
            telemetry,
            ..
        } = self;
        telemetry.step(report, now.t_s, |m| {
            writer.write(m, signer.as_mut(), now.unix_s, out)
        });
    }

    /// A companion's pose for the autopilot's EKF (see [`crate::odometry_from_pose_fix`]).
    pub fn odometry(
        &mut self,
        fix: &PoseFix,
        height_m: Option<f32>,
        now: LinkTime,
        out: &mut Vec<u8>,
    ) {
        self.send(
            &MavMessage::ODOMETRY(odometry_from_pose_fix(fix, height_m)),
            now,
            out,
        );
    }

    /// OBSTACLE_DISTANCE of one revolution, outside the telemetry schedule (a companion sends
    /// one per revolution).
    pub fn obstacle_distance(&mut self, beams: &[Beam], now: LinkTime, out: &mut Vec<u8>) {
        let ranges = self.telemetry.ranges();
        self.send(
            &MavMessage::OBSTACLE_DISTANCE(obstacle_distance(beams, ranges.lidar, now.t_s)),
            now,
            out,
        );
    }

    /// A STATUSTEXT of the caller's (text beyond 50 bytes is cut).
    pub fn statustext(
        &mut self,
        severity: MavSeverity,
        text: &str,
        now: LinkTime,
        out: &mut Vec<u8>,
    ) {
        self.send(&statustext(severity, text), now, out);
    }

    /// Any message, framed and (with a key) signed like the rest.
    pub fn send(&mut self, message: &MavMessage, now: LinkTime, out: &mut Vec<u8>) {
        self.writer
            .write(message, self.signer.as_mut(), now.unix_s, out);
    }

    /// COMMAND_ACK for a command the autopilot has decided on (core's `Outputs::ground_ack`).
    pub fn acknowledge(
        &mut self,
        to: AckTo,
        result: CommandResult,
        now: LinkTime,
        out: &mut Vec<u8>,
    ) {
        self.send(
            &MavMessage::COMMAND_ACK(ack(&to, mav_result(result))),
            now,
            out,
        );
    }

    /// Feeds received bytes (any split, any garbage). Pushes an event for each accepted
    /// message onto `events`; appends the link's own immediate answers (COMMAND_ACK for
    /// commands nobody could carry out) to `replies`.
    pub fn receive(
        &mut self,
        bytes: &[u8],
        now: LinkTime,
        events: &mut Vec<InboundEvent>,
        replies: &mut Vec<u8>,
    ) {
        let mut scanner = core::mem::take(&mut self.scanner);
        scanner.extend(bytes);
        while let Some(frame) = scanner.next_frame(&mut self.counters) {
            self.handle(frame, now, events, replies);
        }
        self.scanner = scanner;
    }

    fn handle(
        &mut self,
        frame: Frame<'_>,
        now: LinkTime,
        events: &mut Vec<InboundEvent>,
        replies: &mut Vec<u8>,
    ) {
        let authentic = match (&mut self.signer, frame.signed) {
            (Some(signer), true) => {
                self.verify_buf.as_mut_slice()[..frame.bytes.len()].copy_from_slice(frame.bytes);
                match signer.verify(&self.verify_buf, now.unix_s) {
                    Ok(()) => true,
                    Err(SignatureFault::Bad) => return self.counters.bad_signature += 1,
                    Err(SignatureFault::Replayed) => return self.counters.replayed += 1,
                }
            }
            // Without a key a signature cannot be checked; the frame counts as unsigned.
            _ => false,
        };
        let Ok(message) =
            <MavMessage as mavlink::Message>::parse(frame.version, frame.message_id, frame.payload)
        else {
            return self.counters.malformed += 1;
        };
        let from = Peer {
            system_id: frame.system_id,
            component_id: frame.component_id,
        };
        let own_autopilot = Peer {
            system_id: self.writer.system_id(),
            component_id: COMPONENT_AUTOPILOT,
        };
        if self.writer.component_id() == COMPONENT_ONBOARD_COMPUTER && from == own_autopilot {
            if let Some(sample) = estimate_sample(&message) {
                return events.push(InboundEvent::Estimate(sample));
            }
        }
        match message {
            MavMessage::HEARTBEAT(h) if h.mavtype == MavType::MAV_TYPE_GCS => {
                // With a key, only a signed heartbeat keeps the ground link alive: an unsigned
                // one could otherwise hold off the link-lost failsafe for a station that is gone.
                if self.signer.is_some() && !authentic {
                    return self.counters.unsigned += 1;
                }
                events.push(InboundEvent::GroundHeartbeat {
                    system_id: frame.system_id,
                });
            }
            MavMessage::COMMAND_LONG(c) => {
                if self.admit(c.target_system, c.target_component, Some(authentic)) {
                    let to = AckTo {
                        command: c.command,
                        system_id: from.system_id,
                        component_id: from.component_id,
                    };
                    match ground_command(&c) {
                        Ok(command) => events.push(InboundEvent::Command {
                            command,
                            ack: Some(to),
                        }),
                        Err(result) => {
                            self.send(&MavMessage::COMMAND_ACK(ack(&to, result)), now, replies)
                        }
                    }
                }
            }
            MavMessage::MANUAL_CONTROL(m) => {
                // MANUAL_CONTROL names no component: any component of this system may take it.
                if self.admit(m.target, 0, Some(authentic)) {
                    match sticks(&m) {
                        Some(s) => events.push(InboundEvent::Command {
                            command: GroundCommand::Sticks(s),
                            ack: None,
                        }),
                        None => self.counters.malformed += 1,
                    }
                }
            }
            MavMessage::PARAM_REQUEST_LIST(p) => {
                if self.admit(p.target_system, p.target_component, None) {
                    events.push(InboundEvent::Param {
                        request: ParamRequest::List,
                        from,
                    });
                }
            }
            MavMessage::PARAM_REQUEST_READ(p) => {
                if self.admit(p.target_system, p.target_component, None) {
                    let which = match u16::try_from(p.param_index) {
                        Ok(i) => ParamRef::Index(i),
                        Err(_) => {
                            ParamRef::Name(crate::params::ParamName::from_wire(p.param_id.into()))
                        }
                    };
                    events.push(InboundEvent::Param {
                        request: ParamRequest::Read(which),
                        from,
                    });
                }
            }
            MavMessage::PARAM_SET(p) => {
                if self.admit(p.target_system, p.target_component, Some(authentic)) {
                    if self.param_limit.admit(now.t_s) {
                        let name = crate::params::ParamName::from_wire(p.param_id.into());
                        events.push(InboundEvent::Param {
                            request: ParamRequest::Set {
                                name,
                                value: p.param_value,
                            },
                            from,
                        });
                    } else {
                        self.counters.rate_limited += 1;
                    }
                }
            }
            _ => self.counters.not_handled += 1,
        }
    }

    /// Whether a message addressed to (`system`, `component`) is this end's to act on;
    /// `authentic` is `Some` for state-changing messages (whether the signature checked out).
    /// Counts the refusal otherwise.
    fn admit(&mut self, system: u8, component: u8, authentic: Option<bool>) -> bool {
        // 0 is MAVLink's broadcast address for both.
        let for_me = (system == 0 || system == self.writer.system_id())
            && (component == 0 || component == self.writer.component_id());
        if !for_me {
            self.counters.other_target += 1;
            return false;
        }
        if self.signer.is_some() && authentic == Some(false) {
            self.counters.unsigned += 1;
            return false;
        }
        true
    }

    /// Answers a parameter request from `store`: PARAM_VALUE for reads and accepted sets (all
    /// parameters for a list request, in index order), PARAM_ERROR for an unknown parameter, and
    /// for a refused value PARAM_ERROR, PARAM_VALUE with the unchanged value (what a ground
    /// station that predates PARAM_ERROR waits for) and a STATUSTEXT saying why.
    pub fn serve_param(
        &mut self,
        request: &ParamRequest,
        from: Peer,
        store: &mut dyn ParameterStore,
        now: LinkTime,
        out: &mut Vec<u8>,
    ) {
        crate::param_replies::serve(self, request, from, store, now, out);
    }
}
