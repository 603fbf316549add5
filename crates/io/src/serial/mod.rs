//! Lidar devices on the std side: the core's sans-I/O decoders behind one device switch, raw
//! captures decoded into CARMEN records, and recording from a serial port with timeouts.

mod capture;
mod device;
mod port;

pub use capture::{decode_capture, DecodeSummary};
pub use device::{stream_commands, DecodedScan, Device, DeviceDecoder};
pub use port::{record, RecordError, RecordOptions, Recorded};
