//! Where a MAVLink link goes (`udpout:HOST:PORT`, `udpin:HOST:PORT`, `serial:DEV:BAUD`, the
//! endpoint syntax of MAVProxy and pymavlink) and the port that carries its bytes without ever
//! blocking the caller: a flight loop that waits on a radio is a flight loop that falls.
//!
//! What cannot go out at once is dropped and counted ([`PortCounters`]), never queued: on a
//! link whose messages are periodic, the next one says the same thing newer.

use std::io::{self, ErrorKind, Read, Write};
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::time::Duration;

/// Where the link's bytes go.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Endpoint {
    /// Send to this address (the ground station listens there; its answers come back to the
    /// port we send from).
    UdpOut(SocketAddr),
    /// Listen on this address; answer whoever sent last.
    UdpIn(SocketAddr),
    /// A serial device (a telemetry radio, a flight controller's TELEM port) at this baud rate.
    Serial { path: String, baud: u32 },
}

impl Endpoint {
    /// Parses `udpout:HOST:PORT`, `udpin:HOST:PORT` or `serial:DEV:BAUD`; the error says what
    /// was expected.
    pub fn parse(text: &str) -> Result<Self, String> {
        const FORMS: &str = "expected udpout:HOST:PORT, udpin:HOST:PORT or serial:DEVICE:BAUD";
        let (kind, rest) = text
            .split_once(':')
            .ok_or_else(|| format!("`{text}`: {FORMS}"))?;
        let (head, tail) = rest
            .rsplit_once(':')
            .ok_or_else(|| format!("`{text}`: {FORMS}"))?;
        match kind {
            "udpout" | "udpin" => {
                let port: u16 = tail
                    .parse()
                    .map_err(|_| format!("`{text}`: port `{tail}` is not a number 0-65535"))?;
                let addr = (head, port)
                    .to_socket_addrs()
                    .map_err(|e| format!("`{text}`: host `{head}`: {e}"))?
                    .next()
                    .ok_or_else(|| format!("`{text}`: host `{head}` has no address"))?;
                if kind == "udpout" {
                    if port == 0 {
                        return Err(format!("`{text}`: udpout needs the ground station's port"));
                    }
                    Ok(Endpoint::UdpOut(addr))
                } else {
                    Ok(Endpoint::UdpIn(addr))
                }
            }
            "serial" => {
                let baud: u32 =
                    tail.parse().ok().filter(|b| *b > 0).ok_or_else(|| {
                        format!("`{text}`: baud `{tail}` is not a positive number")
                    })?;
                if head.is_empty() {
                    return Err(format!("`{text}`: no device"));
                }
                Ok(Endpoint::Serial {
                    path: head.to_string(),
                    baud,
                })
            }
            _ => Err(format!("`{text}`: unknown kind `{kind}`; {FORMS}")),
        }
    }
}

impl std::fmt::Display for Endpoint {
    /// The endpoint as it is written on the command line.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Endpoint::UdpOut(a) => write!(f, "udpout:{}:{}", a.ip(), a.port()),
            Endpoint::UdpIn(a) => write!(f, "udpin:{}:{}", a.ip(), a.port()),
            Endpoint::Serial { path, baud } => write!(f, "serial:{path}:{baud}"),
        }
    }
}

/// What a port did with the bytes handed to it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PortCounters {
    /// Writes that went out whole (datagrams, or frames on a serial line).
    pub sent: u64,
    pub sent_bytes: u64,
    /// Writes dropped because the socket or line could not take them at once.
    pub dropped_busy: u64,
    /// Writes dropped on another error (no route, the peer's port closed, a serial fault).
    pub send_errors: u64,
    /// Writes dropped on a `udpin` port before any ground station had spoken.
    pub dropped_no_peer: u64,
    /// Reads that returned bytes, and how many.
    pub received: u64,
    pub received_bytes: u64,
    /// Reads that failed other than by having nothing to read.
    pub receive_errors: u64,
}

enum Carrier {
    Udp {
        socket: UdpSocket,
        /// Where writes go: the configured ground station, or on `udpin` the last sender.
        peer: Option<SocketAddr>,
        /// `udpin`: follow whoever sent last.
        follow: bool,
    },
    Serial(Box<dyn serialport::SerialPort>),
}

/// A link's port: writes and reads that return at once.
pub struct LinkPort {
    carrier: Carrier,
    counters: PortCounters,
}

impl LinkPort {
    /// Opens `endpoint`; the error names it.
    pub fn open(endpoint: &Endpoint) -> io::Result<Self> {
        let carrier = match endpoint {
            Endpoint::UdpOut(addr) => {
                let any: SocketAddr = if addr.is_ipv4() {
                    ([0, 0, 0, 0], 0).into()
                } else {
                    (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
                };
                let socket = UdpSocket::bind(any)?;
                socket.set_nonblocking(true)?;
                Carrier::Udp {
                    socket,
                    peer: Some(*addr),
                    follow: false,
                }
            }
            Endpoint::UdpIn(addr) => {
                let socket = UdpSocket::bind(addr)?;
                socket.set_nonblocking(true)?;
                Carrier::Udp {
                    socket,
                    peer: None,
                    follow: true,
                }
            }
            Endpoint::Serial { path, baud } => {
                let port = serialport::new(path, *baud)
                    .timeout(Duration::ZERO)
                    .open()
                    .map_err(io::Error::other)?;
                Carrier::Serial(port)
            }
        };
        Ok(Self {
            carrier,
            counters: PortCounters::default(),
        })
    }

    /// The local address of a UDP port (where a ground station's answers arrive).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        match &self.carrier {
            Carrier::Udp { socket, .. } => socket.local_addr().ok(),
            Carrier::Serial(_) => None,
        }
    }

    /// Sends `bytes` as one datagram (or writes them to the line) if that can be done now;
    /// otherwise drops and counts them. Returns whether they went out.
    pub fn send(&mut self, bytes: &[u8]) -> bool {
        let result = match &mut self.carrier {
            Carrier::Udp { socket, peer, .. } => match peer {
                Some(p) => socket.send_to(bytes, *p),
                None => {
                    self.counters.dropped_no_peer += 1;
                    return false;
                }
            },
            Carrier::Serial(port) => port.write(bytes),
        };
        match result {
            Ok(n) if n == bytes.len() => {
                self.counters.sent += 1;
                self.counters.sent_bytes += n as u64;
                true
            }
            // A partial write on a serial line: the frame is broken; the receiver's parser
            // resynchronises on the next start byte.
            Ok(_) => {
                self.counters.dropped_busy += 1;
                false
            }
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                self.counters.dropped_busy += 1;
                false
            }
            Err(_) => {
                self.counters.send_errors += 1;
                false
            }
        }
    }

    /// Reads what has arrived into `buf`, if anything; never waits.
    pub fn receive<'b>(&mut self, buf: &'b mut [u8]) -> Option<&'b [u8]> {
        let result = match &mut self.carrier {
            Carrier::Udp {
                socket,
                peer,
                follow,
            } => socket.recv_from(buf).map(|(n, from)| {
                if *follow {
                    *peer = Some(from);
                }
                n
            }),
            Carrier::Serial(port) => match port.bytes_to_read() {
                Ok(0) => return None,
                Ok(_) => port.read(buf),
                Err(e) => Err(io::Error::other(e)),
            },
        };
        match result {
            Ok(0) => None,
            Ok(n) => {
                self.counters.received += 1;
                self.counters.received_bytes += n as u64;
                Some(&buf[..n])
            }
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => None,
            // ICMP "port unreachable" from a previous datagram surfaces here on some systems:
            // the ground station is not listening yet, which is no reason to stop.
            Err(_) => {
                self.counters.receive_errors += 1;
                None
            }
        }
    }

    pub fn counters(&self) -> PortCounters {
        self.counters
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_parse_and_bad_ones_say_what_is_wrong() {
        assert_eq!(
            Endpoint::parse("udpout:127.0.0.1:14550"),
            Ok(Endpoint::UdpOut(([127, 0, 0, 1], 14550).into()))
        );
        for text in [
            "udpout:127.0.0.1:14550",
            "udpin:0.0.0.0:1",
            "serial:/dev/ttyS0:115200",
        ] {
            assert_eq!(Endpoint::parse(text).unwrap().to_string(), text);
        }
        assert_eq!(
            Endpoint::parse("udpin:0.0.0.0:14551"),
            Ok(Endpoint::UdpIn(([0, 0, 0, 0], 14551).into()))
        );
        assert_eq!(
            Endpoint::parse("serial:/dev/ttyUSB0:57600"),
            Ok(Endpoint::Serial {
                path: "/dev/ttyUSB0".into(),
                baud: 57600
            })
        );
        for (bad, says) in [
            ("udp:1.2.3.4:5", "unknown kind"),
            ("udpout:127.0.0.1", "expected"),
            ("udpout:127.0.0.1:port", "not a number"),
            ("udpout:127.0.0.1:0", "port"),
            ("udpout:127.0.0.1:70000", "not a number"),
            ("serial:/dev/ttyUSB0:fast", "baud"),
            ("serial::57600", "no device"),
            ("14550", "expected"),
        ] {
            let e = Endpoint::parse(bad).unwrap_err();
            assert!(e.contains(says) && e.contains(bad), "{bad}: {e}");
        }
    }

    #[test]
    fn a_udp_port_sends_receives_and_follows_its_peer_without_waiting() {
        let ground = UdpSocket::bind("127.0.0.1:0").unwrap();
        let ground_addr = ground.local_addr().unwrap();
        let mut out = LinkPort::open(&Endpoint::UdpOut(ground_addr)).unwrap();
        let mut buf = [0u8; 64];
        // Nothing has arrived: the read returns at once.
        assert_eq!(out.receive(&mut buf), None);
        assert!(out.send(b"hello"));
        let (n, from) = ground.recv_from(&mut buf).unwrap();
        assert_eq!(&buf[..n], b"hello");
        // The answer comes back to the port the vehicle sends from.
        ground.send_to(b"ack", from).unwrap();
        let mut got = None;
        for _ in 0..1000 {
            if let Some(b) = out.receive(&mut buf) {
                got = Some(b.to_vec());
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        assert_eq!(got.as_deref(), Some(&b"ack"[..]));

        // udpin: nothing goes out until a ground station has spoken, then to it.
        let mut inn = LinkPort::open(&Endpoint::UdpIn(([127, 0, 0, 1], 0).into())).unwrap();
        assert!(!inn.send(b"early"));
        assert_eq!(inn.counters().dropped_no_peer, 1);
        ground.send_to(b"hi", inn.local_addr().unwrap()).unwrap();
        for _ in 0..1000 {
            if inn.receive(&mut buf).is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        assert!(inn.send(b"late"));
        let (n, _) = ground.recv_from(&mut buf).unwrap();
        assert_eq!(&buf[..n], b"late");
        let c = inn.counters();
        assert_eq!((c.sent, c.received), (1, 1));
    }
}
