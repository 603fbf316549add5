//! Where MAVLink goes: `udpout:HOST:PORT` (datagrams to a ground station or an autopilot's UDP
//! port, replies read from the same socket) or `serial:DEVICE:BAUD` (an autopilot's telemetry
//! port), the forms MAVProxy and the autopilots' own tools use.
//!
//! Neither ever blocks its caller: a vehicle's loop or a lidar's read loop must not wait on the
//! network, so a datagram or frame that cannot go out at once is dropped and counted.

use std::fmt;
use std::io::{self, Read, Write};
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::str::FromStr;
use std::time::Duration;

/// Line speeds an autopilot's telemetry port can be set to.
pub const SERIAL_BAUD_RANGE: (u32, u32) = (1200, 4_000_000);

/// A MAVLink endpoint as given on the command line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Endpoint {
    /// Send datagrams to this address (resolved once, when parsed).
    UdpOut { host: String, addr: SocketAddr },
    /// A serial port and its line speed.
    Serial { device: String, baud: u32 },
}

const FORMS: &str = "udpout:HOST:PORT or serial:DEVICE:BAUD";

impl FromStr for Endpoint {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let bad = |why: &str| format!("'{s}': {why} (expected {FORMS})");
        if let Some(rest) = s.strip_prefix("udpout:") {
            let (host, port) = rest.rsplit_once(':').ok_or_else(|| bad("no port"))?;
            let port: u16 = port
                .parse()
                .ok()
                .filter(|p| *p > 0)
                .ok_or_else(|| bad("the port is not a number in [1, 65535]"))?;
            let host_only = host.trim_start_matches('[').trim_end_matches(']');
            if host_only.is_empty() {
                return Err(bad("no host"));
            }
            let addr = (host_only, port)
                .to_socket_addrs()
                .map_err(|e| bad(&format!("cannot resolve the host: {e}")))?
                .next()
                .ok_or_else(|| bad("the host has no address"))?;
            return Ok(Endpoint::UdpOut {
                host: host_only.to_string(),
                addr,
            });
        }
        if let Some(rest) = s.strip_prefix("serial:") {
            let (device, baud) = rest.rsplit_once(':').ok_or_else(|| bad("no baud rate"))?;
            let (lo, hi) = SERIAL_BAUD_RANGE;
            let baud: u32 = baud
                .parse()
                .ok()
                .filter(|b| (lo..=hi).contains(b))
                .ok_or_else(|| bad(&format!("the baud rate is not a number in [{lo}, {hi}]")))?;
            if device.is_empty() {
                return Err(bad("no device"));
            }
            return Ok(Endpoint::Serial {
                device: device.to_string(),
                baud,
            });
        }
        Err(bad("unknown kind"))
    }
}

impl fmt::Display for Endpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Endpoint::UdpOut { addr, .. } => write!(f, "udpout:{addr}"),
            Endpoint::Serial { device, baud } => write!(f, "serial:{device}:{baud}"),
        }
    }
}

/// What happened to one outgoing message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sent {
    Sent,
    /// The way out was full, or the peer is not listening (yet): dropped, and counted.
    Dropped,
}

/// An open endpoint. Sends and reads return at once.
pub enum Transport {
    Udp(UdpSocket),
    Serial(Box<dyn serialport::SerialPort>),
}

impl Endpoint {
    /// Opens the endpoint; the error names it and says what failed.
    pub fn open(&self) -> Result<Transport, String> {
        match self {
            Endpoint::UdpOut { addr, .. } => {
                let local: SocketAddr = if addr.is_ipv4() {
                    "0.0.0.0:0"
                } else {
                    "[::]:0"
                }
                .parse()
                .map_err(|e| format!("{self}: {e}"))?;
                let socket = UdpSocket::bind(local)
                    .and_then(|s| s.connect(addr).map(|()| s))
                    .and_then(|s| s.set_nonblocking(true).map(|()| s))
                    .map_err(|e| format!("{self}: cannot open a UDP socket: {e}"))?;
                Ok(Transport::Udp(socket))
            }
            Endpoint::Serial { device, baud } => serialport::new(device, *baud)
                .timeout(Duration::ZERO)
                .open()
                .map(Transport::Serial)
                .map_err(|e| format!("{self}: cannot open: {e}")),
        }
    }
}

impl Transport {
    /// Sends one whole MAVLink frame (a datagram on UDP). Errors that only mean "not now" (the
    /// socket buffer full, nobody listening on the port yet) drop the frame; anything else
    /// (the serial device gone) is returned.
    pub fn send(&mut self, frame: &[u8]) -> io::Result<Sent> {
        let result = match self {
            Transport::Udp(s) => s.send(frame).map(|_| ()),
            Transport::Serial(p) => p.write_all(frame),
        };
        match result {
            Ok(()) => Ok(Sent::Sent),
            Err(e) if is_transient(&e) => Ok(Sent::Dropped),
            Err(e) => Err(e),
        }
    }

    /// Reads what has arrived (a datagram, or the bytes waiting on the line); 0 when nothing.
    pub fn recv(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let result = match self {
            Transport::Udp(s) => s.recv(buf),
            Transport::Serial(p) => p.read(buf),
        };
        match result {
            Ok(n) => Ok(n),
            Err(e) if is_transient(&e) => Ok(0),
            Err(e) => Err(e),
        }
    }
}

/// "Not now" rather than "broken": a full buffer, a timeout of a zero-wait port, or a UDP peer
/// that is not listening yet (Linux reports the ICMP port-unreachable of an earlier datagram).
fn is_transient(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::WouldBlock
            | io::ErrorKind::TimedOut
            | io::ErrorKind::Interrupted
            | io::ErrorKind::ConnectionRefused
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_two_forms_parse_and_print_back() {
        let udp: Endpoint = "udpout:127.0.0.1:14550".parse().unwrap();
        assert_eq!(udp.to_string(), "udpout:127.0.0.1:14550");
        let serial: Endpoint = "serial:/dev/ttyAMA0:921600".parse().unwrap();
        assert_eq!(
            serial,
            Endpoint::Serial {
                device: "/dev/ttyAMA0".into(),
                baud: 921_600
            }
        );
        let v6: Endpoint = "udpout:[::1]:14550".parse().unwrap();
        assert!(matches!(v6, Endpoint::UdpOut { addr, .. } if addr.is_ipv6()));
    }

    #[test]
    fn malformed_endpoints_say_what_is_wrong_and_what_is_expected() {
        for (text, why) in [
            ("udp:127.0.0.1:14550", "unknown kind"),
            ("udpout:127.0.0.1", "no port"),
            ("udpout:127.0.0.1:0", "port is not a number"),
            ("udpout::14550", "no host"),
            ("serial:/dev/ttyS0", "no baud rate"),
            ("serial:/dev/ttyS0:12", "baud rate is not a number"),
            ("serial::57600", "no device"),
        ] {
            let err = text.parse::<Endpoint>().unwrap_err();
            assert!(err.contains(why) && err.contains(FORMS), "{text}: {err}");
        }
    }

    #[test]
    fn udp_frames_arrive_whole_and_a_missing_listener_only_drops() {
        let peer = UdpSocket::bind("127.0.0.1:0").unwrap();
        let to: Endpoint = format!("udpout:{}", peer.local_addr().unwrap())
            .parse()
            .unwrap();
        let mut t = to.open().unwrap();
        assert_eq!(t.send(b"\xfdframe").unwrap(), Sent::Sent);
        peer.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        let mut buf = [0u8; 64];
        let n = peer.recv(&mut buf).unwrap();
        assert_eq!(&buf[..n], b"\xfdframe");
        drop(peer);
        // Nobody listens now: the refusals that come back are drops, never errors.
        for _ in 0..3 {
            assert!(t.send(b"x").is_ok());
            assert_eq!(t.recv(&mut buf).unwrap(), 0);
        }
    }

    #[test]
    fn a_serial_port_that_does_not_exist_is_a_clear_error() {
        let e: Endpoint = "serial:/dev/plumbline-no-such-port:57600".parse().unwrap();
        let err = e.open().err().unwrap();
        assert!(
            err.starts_with("serial:/dev/plumbline-no-such-port:57600: cannot open"),
            "{err}"
        );
    }
}
