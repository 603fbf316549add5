//! SCIP 2.0 commands (Hokuyo URG series), written into a caller's buffer.
//!
//! A command is two letters, fixed-width decimal parameters and a line feed
//! (SCIP 2.0 specification C-42-03320B, section 7). Ranges are checked here so a bad request
//! is an error on the host, not a status code from the sensor.

/// Characters per range value in a reply: MD/GD send 3 (18 bits), MS/GS send 2 (12 bits).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    TwoChar,
    ThreeChar,
}

impl Encoding {
    pub fn chars(self) -> usize {
        match self {
            Encoding::TwoChar => 2,
            Encoding::ThreeChar => 3,
        }
    }
}

/// The commands Plumbline sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// `SCIP2.0`: switch a sensor still speaking SCIP 1.1.
    Scip2,
    /// `BM`: laser on (needed before GD/GS).
    LaserOn,
    /// `QT`: laser off, ends an MD/MS stream.
    LaserOff,
    /// `VV`: version information.
    Version,
    /// `PP`: sensor parameters (steps, range limits, front step, motor speed).
    Parameters,
    /// `GD`/`GS`: one scan of steps `start..=end`, `cluster` steps merged into one value.
    Get {
        start: u16,
        end: u16,
        cluster: u8,
        encoding: Encoding,
    },
    /// `MD`/`MS`: `scans` scans (0 = until `QT`), skipping `interval` scans between each.
    Stream {
        start: u16,
        end: u16,
        cluster: u8,
        interval: u8,
        scans: u8,
        encoding: Encoding,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommandError {
    /// A parameter does not fit its field or `start > end`.
    OutOfRange,
    /// The buffer is shorter than the command.
    BufferTooSmall { needed: usize },
}

/// Appends to a fixed buffer, failing instead of panicking when it is full.
struct Cursor<'a> {
    out: &'a mut [u8],
    len: usize,
}

impl Cursor<'_> {
    fn put(&mut self, bytes: &[u8]) {
        if let Some(dst) = self.out.get_mut(self.len..self.len + bytes.len()) {
            dst.copy_from_slice(bytes);
        }
        self.len += bytes.len();
    }

    fn digits(&mut self, value: u16, width: u32) {
        for i in (0..width).rev() {
            self.put(&[b'0' + (value / 10u16.pow(i) % 10) as u8]);
        }
    }
}

fn check(ok: bool) -> Result<(), CommandError> {
    ok.then_some(()).ok_or(CommandError::OutOfRange)
}

/// Writes `cmd` and its line feed into `out`; returns the number of bytes written.
pub fn write_command(cmd: &Command, out: &mut [u8]) -> Result<usize, CommandError> {
    let mut c = Cursor { out, len: 0 };
    match *cmd {
        Command::Scip2 => c.put(b"SCIP2.0"),
        Command::LaserOn => c.put(b"BM"),
        Command::LaserOff => c.put(b"QT"),
        Command::Version => c.put(b"VV"),
        Command::Parameters => c.put(b"PP"),
        Command::Get {
            start,
            end,
            cluster,
            encoding,
        } => {
            check(start <= end && end <= 9999 && cluster <= 99)?;
            c.put(if encoding == Encoding::ThreeChar {
                b"GD"
            } else {
                b"GS"
            });
            c.digits(start, 4);
            c.digits(end, 4);
            c.digits(cluster.into(), 2);
        }
        Command::Stream {
            start,
            end,
            cluster,
            interval,
            scans,
            encoding,
        } => {
            check(start <= end && end <= 9999 && cluster <= 99 && interval <= 9 && scans <= 99)?;
            c.put(if encoding == Encoding::ThreeChar {
                b"MD"
            } else {
                b"MS"
            });
            c.digits(start, 4);
            c.digits(end, 4);
            c.digits(cluster.into(), 2);
            c.digits(interval.into(), 1);
            c.digits(scans.into(), 2);
        }
    }
    c.put(b"\n");
    if c.len > c.out.len() {
        return Err(CommandError::BufferTooSmall { needed: c.len });
    }
    Ok(c.len)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(cmd: Command) -> ([u8; 32], usize) {
        let mut buf = [0u8; 32];
        let n = write_command(&cmd, &mut buf).unwrap();
        (buf, n)
    }

    #[test]
    fn stream_command_matches_the_specification_example() {
        // The specification's MD example: steps 44..725, no clustering, every scan, one scan.
        let cmd = Command::Stream {
            start: 44,
            end: 725,
            cluster: 0,
            interval: 0,
            scans: 1,
            encoding: Encoding::ThreeChar,
        };
        let (buf, n) = text(cmd);
        assert_eq!(&buf[..n], b"MD0044072500001\n");
    }

    #[test]
    fn get_and_plain_commands() {
        let (buf, n) = text(Command::Get {
            start: 0,
            end: 768,
            cluster: 3,
            encoding: Encoding::TwoChar,
        });
        assert_eq!(&buf[..n], b"GS0000076803\n");
        let (buf, n) = text(Command::LaserOn);
        assert_eq!(&buf[..n], b"BM\n");
    }

    #[test]
    fn bad_parameters_and_short_buffers_are_errors() {
        let bad = Command::Get {
            start: 10,
            end: 9,
            cluster: 0,
            encoding: Encoding::ThreeChar,
        };
        assert_eq!(
            write_command(&bad, &mut [0u8; 32]),
            Err(CommandError::OutOfRange)
        );
        let ok = Command::Get {
            start: 0,
            end: 9,
            cluster: 0,
            encoding: Encoding::ThreeChar,
        };
        assert_eq!(
            write_command(&ok, &mut [0u8; 5]),
            Err(CommandError::BufferTooSmall { needed: 13 })
        );
    }
}
