//! Lidar devices on the std side: the core's sans-I/O decoders behind one device switch, raw
//! captures decoded into CARMEN records, and recording from a serial port with timeouts.

mod capture;
mod device;
mod port;

pub use capture::{
    decode_capture, decode_stream, CaptureError, DecodeSummary, SummaryTally,
    MAX_BYTES_WITHOUT_FRAME,
};
pub use device::{stream_commands, DecodedScan, Device, DeviceDecoder};
pub use port::{open_port, OpenPort, RecordError, RecordOptions, RecordSink, Recorded};
