//! Where the revolutions come from: a lidar on a serial port, a raw capture of one, or a CARMEN
//! log. All three hand the same stamped records to the pipeline, one revolution at a time.

use crate::lidar_cmd::require_frames;
use crate::log_args::{no_scans, report_bad_lines};
use crate::report::CliError;
use plumbline_io::carmen::{open_log, LaserRecord, ReadOptions};
use plumbline_io::input::open_input;
use plumbline_io::serial::{
    decode_stream, open_port, DecodeSummary, DecodedScan, Device, RecordOptions, RecordSink,
};
use std::io;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// One of the three inputs, with what it needs to be read.
pub enum Source {
    Port(RecordOptions),
    Capture {
        path: PathBuf,
        device: Device,
        baud: u32,
    },
    Log {
        path: PathBuf,
        options: ReadOptions,
    },
}

/// What a source said at its end, beyond the revolutions it handed out.
#[derive(Debug, Default)]
pub struct SourceEnd {
    /// The decoder's counts (devices and captures only).
    pub decode: Option<DecodeSummary>,
    /// The port fell silent before the end (a live lidar stopped or was unplugged).
    pub stopped_by_silence: bool,
    /// What ended a live run early after data had come; the run up to then stands.
    pub failure: Option<String>,
}

/// Plays a replay's revolutions at the pace of their stamps, the first one at once.
pub struct Pacer {
    start: Option<(Instant, f64)>,
}

impl Pacer {
    pub fn new() -> Self {
        Self { start: None }
    }

    fn wait_for(&mut self, stamp_s: f64) {
        let (wall, first) = *self.start.get_or_insert((Instant::now(), stamp_s));
        let due = Duration::try_from_secs_f64(stamp_s - first).unwrap_or_default();
        if let Some(left) = due.checked_sub(wall.elapsed()) {
            std::thread::sleep(left);
        }
    }
}

/// Hands every revolution of `source` to `on_scan` as it completes; an error from `on_scan`
/// ends the run. `pacer`: play a replay at the pace of its stamps (a live port is paced by the
/// device).
pub fn each_revolution(
    source: &Source,
    mut pacer: Option<Pacer>,
    mut on_scan: impl FnMut(&LaserRecord) -> Result<(), CliError>,
) -> Result<SourceEnd, CliError> {
    let mut paced = |rec: &LaserRecord| {
        if let Some(p) = pacer.as_mut() {
            p.wait_for(rec.timestamp_s);
        }
        on_scan(rec)
    };
    match source {
        Source::Port(opts) => live(opts, &mut paced),
        Source::Capture { path, device, baud } => {
            let input = open_input(path)?;
            let summary = decode_stream(*device, input.reader, &input.name, *baud, |s| {
                paced(&s.record).map(|()| true)
            })?;
            require_frames(&input.name, *device, &summary)?;
            Ok(SourceEnd {
                decode: Some(summary),
                ..SourceEnd::default()
            })
        }
        Source::Log { path, options } => {
            let (mut reader, _) = open_log(path, options)?;
            let mut any = false;
            while let Some(rec) = reader.next_scan()? {
                any = true;
                paced(&rec)?;
            }
            report_bad_lines(reader.stats());
            if !any {
                return Err(no_scans(path));
            }
            Ok(SourceEnd::default())
        }
    }
}

/// The pipeline as a recorder's sink: the raw bytes are not kept, each scan goes through.
struct Through<'a> {
    on_scan: &'a mut dyn FnMut(&LaserRecord) -> Result<(), CliError>,
    /// Why the pipeline ended the run (the autopilot's port gone).
    stop: Option<CliError>,
}

impl RecordSink for Through<'_> {
    fn raw(&mut self, _bytes: &[u8]) -> io::Result<()> {
        Ok(())
    }

    fn scan(&mut self, scan: &DecodedScan) -> io::Result<()> {
        (self.on_scan)(&scan.record).map_err(|e| {
            let text = e.0.clone();
            self.stop = Some(e);
            io::Error::other(text)
        })
    }
}

fn live(
    opts: &RecordOptions,
    on_scan: &mut dyn FnMut(&LaserRecord) -> Result<(), CliError>,
) -> Result<SourceEnd, CliError> {
    let port = open_port(opts)?;
    let mut sink = Through {
        on_scan,
        stop: None,
    };
    let recorded = port.record(&mut sink)?;
    // A failure of the pipeline itself (the autopilot's port gone) ends the run as an error.
    if let Some(e) = sink.stop {
        return Err(e);
    }
    let end = SourceEnd {
        stopped_by_silence: recorded.stopped_by_silence,
        failure: recorded.failure.map(|f| f.to_string()),
        decode: Some(recorded.summary),
    };
    if let Some(summary) = &end.decode {
        if end.failure.is_none() {
            require_frames(&opts.port, opts.device, summary)?;
        }
    }
    Ok(end)
}
