//! Recording from a serial port: raw bytes to a file, decoded scans to a callback. Every wait
//! is bounded: reads time out after `READ_TIMEOUT`, the whole recording stops after `duration`,
//! and a port silent for `idle_timeout` ends it early: an error when nothing came at all
//! (wrong port, device off), a reported fault in [`Recorded`] when the stream stopped.

use super::capture::{DecodeSummary, SummaryTally};
use super::device::{stream_commands, DecodedScan, Device, DeviceDecoder};
use std::io::{self, Read, Write};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

const READ_TIMEOUT: Duration = Duration::from_millis(100);

#[derive(Clone, Debug)]
pub struct RecordOptions {
    pub device: Device,
    pub port: String,
    pub baud: u32,
    pub duration: Duration,
    /// Silence longer than this ends the recording.
    pub idle_timeout: Duration,
}

/// A recording that got data. It may still have ended in a failure; what was kept is in the
/// summary either way, since that is when it matters most.
#[derive(Debug)]
pub struct Recorded {
    pub summary: DecodeSummary,
    /// True when the device went silent before `duration` was up (stream stopped, unplugged).
    pub stopped_by_silence: bool,
    /// The failure that ended the recording after data had come (port gone, disk full).
    pub failure: Option<RecordError>,
}

#[derive(Debug)]
pub enum RecordError {
    Open {
        port: String,
        source: serialport::Error,
    },
    /// The port failed while reading or sending the start command (unplugged, closed).
    Read {
        port: String,
        source: io::Error,
    },
    Silent {
        port: String,
        idle: Duration,
    },
    /// The sink refused bytes or a scan (disk full); its error names the file.
    Write(io::Error),
}

impl std::fmt::Display for RecordError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RecordError::Open { port, source } => write!(f, "{port}: cannot open: {source}"),
            RecordError::Read { port, source } => {
                write!(f, "{port}: read or write failed (device gone?): {source}")
            }
            RecordError::Silent { port, idle } => write!(
                f,
                "{port}: no data for {:.1} s (device off, unplugged or wrong port?)",
                idle.as_secs_f64()
            ),
            RecordError::Write(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for RecordError {}

/// Where a recording goes. Nothing reaches it until the device has sent its first bytes, so a
/// sink may wait for the first `raw` call to replace files it would otherwise destroy.
pub trait RecordSink {
    /// Bytes exactly as read, in order.
    fn raw(&mut self, bytes: &[u8]) -> io::Result<()>;
    /// A decoded, stamped scan, as soon as it is complete.
    fn scan(&mut self, scan: &DecodedScan) -> io::Result<()>;
}

fn now_s() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// A serial port, open and ready to record.
pub struct OpenPort {
    port: Box<dyn serialport::SerialPort>,
    opts: RecordOptions,
}

/// Opens the port; the first step of a recording, taken before any output is touched.
pub fn open_port(opts: &RecordOptions) -> Result<OpenPort, RecordError> {
    let port = serialport::new(&opts.port, opts.baud)
        .timeout(READ_TIMEOUT)
        .open()
        .map_err(|source| RecordError::Open {
            port: opts.port.clone(),
            source,
        })?;
    Ok(OpenPort {
        port,
        opts: opts.clone(),
    })
}

impl OpenPort {
    /// Records until `duration` has passed or the port falls silent. Each scan is stamped with
    /// the host clock at the time its first byte arrived (estimated from the bytes read since,
    /// at the device's data rate or the line's 10 bits a byte). An error is returned only when
    /// no data came at all; later failures end the recording with its last partial revolution
    /// decoded and are reported in [`Recorded::failure`].
    pub fn record(mut self, sink: &mut dyn RecordSink) -> Result<Recorded, RecordError> {
        let opts = &self.opts;
        let port = &mut self.port;
        let (start_cmd, stop_cmd) = stream_commands(opts.device);
        let read_error = |source| RecordError::Read {
            port: opts.port.clone(),
            source,
        };
        port.write_all(&start_cmd).map_err(read_error)?;
        let mut decoder = DeviceDecoder::new(opts.device);
        let mut tally = SummaryTally::default();
        let bytes_per_s = f64::from(opts.baud.max(1)) / 10.0;
        let start = Instant::now();
        let mut last_data = start;
        let mut buf = [0u8; 4096];
        let mut total: u64 = 0;
        let mut emit = |mut scan: DecodedScan, total: u64, sink: &mut dyn RecordSink| {
            let rate = scan.bytes_per_s.filter(|r| *r > 0.0).unwrap_or(bytes_per_s);
            scan.stamp(now_s() - (total - scan.first_offset) as f64 / rate);
            tally.add(&scan);
            sink.scan(&scan).map_err(RecordError::Write)
        };
        let (mut stopped_by_silence, mut failure) = (false, None);
        while start.elapsed() < opts.duration {
            let n = match port.read(&mut buf) {
                Ok(n) => n,
                Err(e)
                    if e.kind() == io::ErrorKind::TimedOut
                        || e.kind() == io::ErrorKind::Interrupted =>
                {
                    0
                }
                Err(source) if total == 0 => return Err(read_error(source)),
                Err(source) => {
                    failure = Some(read_error(source));
                    break;
                }
            };
            if n == 0 {
                if last_data.elapsed() >= opts.idle_timeout {
                    if total == 0 {
                        return Err(RecordError::Silent {
                            port: opts.port.clone(),
                            idle: opts.idle_timeout,
                        });
                    }
                    stopped_by_silence = true;
                    break;
                }
                continue;
            }
            last_data = Instant::now();
            if let Err(e) = sink.raw(&buf[..n]) {
                failure = Some(RecordError::Write(e));
                break;
            }
            for &b in &buf[..n] {
                total += 1;
                if let Some(scan) = decoder.push(b) {
                    if let Err(e) = emit(scan, total, sink) {
                        failure.get_or_insert(e);
                    }
                }
            }
            if failure.is_some() {
                break;
            }
        }
        // Best effort: a device that vanished cannot be told to stop, and that is not an error.
        let _ = port.write_all(&stop_cmd);
        // The revolution in progress is data too, whatever ended the recording.
        if let Some(scan) = decoder.finish() {
            if let Err(e) = emit(scan, total, sink) {
                failure.get_or_insert(e);
            }
        }
        Ok(Recorded {
            summary: tally.summary(decoder.stats()),
            stopped_by_silence,
            failure,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_port_that_does_not_exist_is_a_clear_error() {
        let opts = RecordOptions {
            device: Device::Xv11,
            port: "/dev/plumbline-no-such-port".into(),
            baud: 115_200,
            duration: Duration::from_secs(1),
            idle_timeout: Duration::from_secs(1),
        };
        let err = open_port(&opts).err().unwrap();
        let msg = err.to_string();
        assert!(
            msg.starts_with("/dev/plumbline-no-such-port: cannot open"),
            "{msg}"
        );
    }
}
