//! `plumbline sim --mavlink ENDPOINT`: the simulated vehicle as a MAVLink 2 system, so
//! QGroundControl, MAVProxy or a pymavlink script can watch and command a simulated flight.
//!
//! A ground station of the simulator ([`GroundStation`]) that speaks `plumbline-link` over a
//! [`LinkPort`]: after each onboard step it reads what has arrived (without waiting), answers
//! parameter requests, hands one command to the autopilot for the next step, acknowledges the
//! autopilot's decision on the previous one, and sends the telemetry due. Whatever the network
//! does, the vehicle's loop does not wait and does not stop: what cannot be sent at once is
//! dropped and counted.

use clap::Args;
use mavlink::Message;
use plumbline_core::flight::params::ParamError;
use plumbline_core::msgs::{
    BatterySample, CommandResult, GroundAck, GroundCommand, GroundMessages, SonarSample,
};
use plumbline_core::scan::Beam;
use plumbline_io::input::read_text;
use plumbline_io::link_port::{Endpoint, LinkPort, PortCounters};
use plumbline_link::common::MavMessage;
use plumbline_link::{
    frame_span, AckTo, DropCounters, InboundEvent, Link, LinkConfig, LinkTime, ParameterStore,
    SigningKey, TelemetryInput,
};
use plumbline_sim::runner::ground::{GroundStation, Parameters, VehicleReport};
use serde_json::{json, Value};
use std::cell::RefCell;
use std::collections::{BTreeMap, VecDeque};
use std::path::Path;
use std::rc::Rc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

#[derive(Args, Debug)]
pub struct MavlinkArgs {
    /// Be a MAVLink 2 vehicle for a ground station: `udpout:HOST:PORT` sends to a station
    /// listening there (QGroundControl listens on udpout:127.0.0.1:14550), `udpin:HOST:PORT`
    /// listens and answers whoever speaks. Telemetry rates and commands: README.
    #[arg(long, value_name = "ENDPOINT", value_parser = Endpoint::parse)]
    pub mavlink: Option<Endpoint>,
    /// Sign the link with this MAVLink 2 key (64 hex digits, or a file holding them): commands
    /// that change the vehicle's state are then taken only when signed with it.
    #[arg(long, value_name = "HEX|FILE", requires = "mavlink")]
    pub mavlink_key: Option<String>,
}

/// Datagrams read per step at most: a flood waits in the socket's buffer (and overflows there)
/// instead of stalling the flight.
const MAX_READS_PER_STEP: usize = 32;
/// Commands waiting for their step, and commands waiting for the autopilot's answer, at most.
const MAX_PENDING: usize = 16;
/// The socket is read at 100 Hz, as a flight controller's MAVLink receiver polls: reading it
/// after every 2 ms step was most of the link's cost (a failed `recvfrom` each time, 1.3 us a
/// step). A command waits at most this long to be read, then reaches the autopilot at the next
/// step.
const RECEIVE_PERIOD_S: f64 = 0.01;
/// Datagrams stay below a common path MTU; frames are never split across two.
const MAX_DATAGRAM: usize = 1400;

/// The signing key `arg` gives: 64 hex digits, or a file holding them.
pub fn signing_key(arg: &str) -> Result<SigningKey, String> {
    let text = if Path::new(arg).is_file() {
        read_text(Path::new(arg)).map_err(|e| format!("--mavlink-key: {e}"))?
    } else {
        arg.to_string()
    };
    let hex = text.trim();
    let bad = || {
        format!(
            "--mavlink-key: expected 64 hexadecimal digits (a 32-byte key) or a file holding \
             them, got {} characters",
            hex.len()
        )
    };
    if hex.len() != 64 || !hex.is_ascii() {
        return Err(bad());
    }
    let mut secret = [0u8; 32];
    for (i, byte) in secret.iter_mut().enumerate() {
        *byte = u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).map_err(|_| bad())?;
    }
    Ok(SigningKey { secret, link_id: 0 })
}

/// What the link did, shared with the caller for the summary.
#[derive(Clone, Debug, Default)]
pub struct LinkStats {
    pub endpoint: String,
    pub signed: bool,
    pub port: PortCounters,
    pub refused: DropCounters,
    /// Messages that went out, by name.
    pub sent: BTreeMap<&'static str, u64>,
    /// Messages in datagrams the port dropped.
    pub dropped_messages: u64,
    /// Commands handed to the autopilot, and its answers.
    pub commands: u64,
    pub accepted: u64,
    pub refused_by_autopilot: u64,
    /// Commands dropped because more arrived than the autopilot takes (one per step).
    pub commands_dropped: u64,
    /// Time spent in the link per onboard step (receive, encode, send).
    pub steps: u64,
    pub busy: Duration,
    pub busiest: Duration,
}

impl LinkStats {
    pub fn summary(&self) -> Value {
        let r = &self.refused;
        json!({
            "endpoint": self.endpoint,
            "signed": self.signed,
            "sent_messages": self.sent.values().sum::<u64>(),
            "sent_by_type": self.sent,
            "sent_datagrams": self.port.sent,
            "sent_bytes": self.port.sent_bytes,
            "dropped_datagrams": self.port.dropped_busy + self.port.send_errors
                + self.port.dropped_no_peer,
            "dropped_busy": self.port.dropped_busy,
            "send_errors": self.port.send_errors,
            "dropped_no_peer": self.port.dropped_no_peer,
            "dropped_messages": self.dropped_messages,
            "received_datagrams": self.port.received,
            "received_bytes": self.port.received_bytes,
            "receive_errors": self.port.receive_errors,
            "refused": {
                "total": r.refused(),
                "bad_crc": r.bad_crc,
                "unknown_id": r.unknown_id,
                "bad_header": r.bad_header,
                "malformed": r.malformed,
                "other_target": r.other_target,
                "unsigned": r.unsigned,
                "bad_signature": r.bad_signature,
                "replayed": r.replayed,
                "rate_limited": r.rate_limited,
            },
            "skipped_bytes": r.skipped_bytes,
            "not_handled": r.not_handled,
            "commands": self.commands,
            "commands_accepted": self.accepted,
            "commands_refused": self.refused_by_autopilot,
            "commands_dropped": self.commands_dropped,
            "link_step_mean_us": (self.steps > 0)
                .then(|| self.busy.as_secs_f64() * 1e6 / self.steps as f64),
            "link_step_max_us": self.busiest.as_secs_f64() * 1e6,
        })
    }
}

/// Unix time now, never going backwards (signing timestamps must increase).
struct UnixClock {
    last_s: f64,
}

impl UnixClock {
    fn now(&mut self) -> f64 {
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64());
        self.last_s = self.last_s.max(now);
        self.last_s
    }
}

/// The simulated vehicle's MAVLink link.
pub struct MavlinkStation {
    link: Link,
    port: LinkPort,
    clock: UnixClock,
    announced: bool,
    /// Sim time of the next read of the socket (see [`RECEIVE_PERIOD_S`]).
    next_receive_s: f64,
    /// Frames to send at this step.
    out: Vec<u8>,
    rx: Vec<u8>,
    inbound: Vec<InboundEvent>,
    /// Commands received, one handed to the autopilot per step.
    commands: VecDeque<(GroundCommand, Option<AckTo>)>,
    /// Commands handed over whose sender waits for a COMMAND_ACK.
    awaiting: VecDeque<(GroundCommand, AckTo)>,
    /// The newest readings, for the streams that repeat them at their own rate.
    sonar: Option<SonarSample>,
    battery: Option<BatterySample>,
    scan: Option<Vec<Beam>>,
    stats: Rc<RefCell<LinkStats>>,
}

impl MavlinkStation {
    /// Opens the link; the caller keeps the statistics' handle.
    pub fn open(
        endpoint: &Endpoint,
        key: Option<SigningKey>,
    ) -> Result<(Self, Rc<RefCell<LinkStats>>), String> {
        let port = LinkPort::open(endpoint).map_err(|e| format!("--mavlink {endpoint}: {e}"))?;
        let stats = Rc::new(RefCell::new(LinkStats {
            endpoint: endpoint.to_string(),
            signed: key.is_some(),
            ..LinkStats::default()
        }));
        let station = Self {
            link: Link::new(LinkConfig {
                key,
                ..LinkConfig::default()
            }),
            port,
            clock: UnixClock { last_s: 0.0 },
            announced: false,
            next_receive_s: 0.0,
            out: Vec::with_capacity(4 * MAX_DATAGRAM),
            rx: vec![0; 65536],
            inbound: Vec::new(),
            commands: VecDeque::new(),
            awaiting: VecDeque::new(),
            sonar: None,
            battery: None,
            scan: None,
            stats: stats.clone(),
        };
        Ok((station, stats))
    }

    /// COMMAND_ACK for the autopilot's answer to a command this link handed over.
    fn acknowledge(&mut self, ack: &GroundAck, now: LinkTime) {
        let Some(i) = self.awaiting.iter().position(|(c, _)| *c == ack.command) else {
            return;
        };
        let Some((_, to)) = self.awaiting.remove(i) else {
            return;
        };
        let mut stats = self.stats.borrow_mut();
        match ack.result {
            CommandResult::Accepted => stats.accepted += 1,
            _ => stats.refused_by_autopilot += 1,
        }
        self.link.acknowledge(to, ack.result, now, &mut self.out);
    }

    /// Reads what has arrived; returns whether a ground heartbeat was among it.
    fn receive(&mut self, now: LinkTime, params: &mut dyn ParameterStore) -> bool {
        for _ in 0..MAX_READS_PER_STEP {
            let Some(bytes) = self.port.receive(&mut self.rx) else {
                break;
            };
            self.link
                .receive(bytes, now, &mut self.inbound, &mut self.out);
        }
        let mut heartbeat = false;
        for event in self.inbound.drain(..) {
            match event {
                InboundEvent::GroundHeartbeat { .. } => heartbeat = true,
                InboundEvent::Command { command, ack } => {
                    if self.commands.len() >= MAX_PENDING {
                        self.stats.borrow_mut().commands_dropped += 1;
                        if command != GroundCommand::Terminate {
                            continue;
                        }
                        self.commands.pop_back();
                    }
                    // The kill switch goes first.
                    if command == GroundCommand::Terminate {
                        self.commands.push_front((command, ack));
                    } else {
                        self.commands.push_back((command, ack));
                    }
                }
                InboundEvent::Param { request, from } => {
                    self.link
                        .serve_param(&request, from, params, now, &mut self.out)
                }
                // Only a companion's link reads an autopilot's estimate; this one is the
                // autopilot.
                InboundEvent::Estimate(_) => {}
            }
        }
        heartbeat
    }

    /// Sends this step's frames, in datagrams that each hold whole frames.
    fn flush(&mut self) {
        let mut stats = self.stats.borrow_mut();
        let mut rest = &self.out[..];
        while !rest.is_empty() {
            let mut len = 0;
            let mut ids = [0u32; 32];
            let mut n = 0;
            while let Some((frame_len, id)) = frame_span(&rest[len..]) {
                if len > 0 && (len + frame_len > MAX_DATAGRAM || n == ids.len()) {
                    break;
                }
                ids[n] = id;
                n += 1;
                len += frame_len;
            }
            if len == 0 {
                // Not a frame of ours: cannot happen with the link's output; never loop on it.
                break;
            }
            if self.port.send(&rest[..len]) {
                for &id in &ids[..n] {
                    *stats.sent.entry(message_name(id)).or_default() += 1;
                }
            } else {
                stats.dropped_messages += n as u64;
            }
            rest = &rest[len..];
        }
        self.out.clear();
        stats.port = self.port.counters();
        stats.refused = *self.link.counters();
    }
}

fn message_name(id: u32) -> &'static str {
    MavMessage::default_message_from_id(id).map_or("UNKNOWN", |m| m.message_name())
}

impl GroundStation for MavlinkStation {
    fn exchange(
        &mut self,
        v: &VehicleReport<'_>,
        parameters: &mut Parameters<'_>,
    ) -> GroundMessages {
        let started = Instant::now();
        let now = LinkTime {
            t_s: v.t_s,
            unix_s: self.clock.now(),
        };
        if !self.announced {
            self.link.announce(now, &mut self.out);
            self.announced = true;
        }
        if let Some(ack) = &v.outputs.ground_ack {
            self.acknowledge(ack, now);
        }
        let heartbeat = v.t_s >= self.next_receive_s && {
            self.next_receive_s = v.t_s + RECEIVE_PERIOD_S;
            self.receive(now, &mut Registry(parameters))
        };
        self.battery = Some(v.battery);
        self.sonar = v.sonar.or(self.sonar);
        if let Some(beams) = v.scan {
            let scan = self.scan.get_or_insert_with(Vec::new);
            scan.clear();
            scan.extend_from_slice(beams);
        }
        let report = TelemetryInput {
            outputs: v.outputs,
            body_rates_rad_s: v.imu.gyro_rad_s,
            battery: self.battery,
            sonar: self.sonar,
            scan: self.scan.as_deref(),
        };
        self.link.telemetry(&report, now, &mut self.out);
        self.flush();
        let command = self.commands.pop_front().map(|(command, ack)| {
            if let Some(to) = ack {
                if self.awaiting.len() >= MAX_PENDING {
                    self.awaiting.pop_front();
                }
                self.awaiting.push_back((command, to));
            }
            command
        });
        let mut stats = self.stats.borrow_mut();
        stats.commands += u64::from(command.is_some());
        let spent = started.elapsed();
        stats.steps += 1;
        stats.busy += spent;
        stats.busiest = stats.busiest.max(spent);
        GroundMessages { command, heartbeat }
    }
}

/// The autopilot's parameters as the link serves them.
struct Registry<'p, 'a>(&'p mut Parameters<'a>);

impl ParameterStore for Registry<'_, '_> {
    fn count(&self) -> usize {
        self.0.count()
    }

    fn name(&self, index: usize) -> Option<&str> {
        self.0.info(index).map(|p| p.name)
    }

    fn value(&self, index: usize) -> Option<f32> {
        self.0.get(index)
    }

    fn set(&mut self, index: usize, value: f32) -> Result<f32, ParamError> {
        self.0.set(index, value)
    }
}
