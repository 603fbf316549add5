//! Sans-I/O lidar decoders: bytes in, revolutions out.
//!
//! Each decoder is fed one byte at a time by whoever owns the port or the file (the std side in
//! `plumbline-io`, a UART interrupt on a microcontroller, a fuzzer); none reads a clock or a
//! port, so a recorded capture drives exactly the code a live device does. Device conventions
//! (clockwise degrees, step numbers) are converted to Plumbline's [`Scan`](crate::scan::Scan)
//! convention at this edge: counter-clockwise radians, per-beam validity, per-beam time.
//!
//! Malformed input never panics: it is dropped and counted in [`DecodeStats`], and a decoder
//! resynchronises on the next frame start. Missing data leaves invalid beams at the angles it
//! would have filled; beams are never shifted to close a gap.
//!
//! State sizes, the RAM a device costs (bytes, x86-64 `core::mem::size_of`; printed and bounded
//! by `tests/lidar_state_sizes.rs`):
//!
//! | decoder | state | revolution it hands out |
//! |---|---|---|
//! | [`xv11_revolution::Xv11Decoder`] (fw >= 2.4) | 1568 | 1472 (`Revolution`) |
//! | [`xv11_old::Xv11OldDecoder`] (fw < 2.4) | 3008 | 1472 |
//! | [`scip::ScipDecoder`]`<769>` (URG-04LX) | 3264 | 3096 (`ScipScan<769>`) |
//! | [`rplidar::RplidarDecoder`]`<800>` | 4880 | 4816 (`RplidarRevolution<800>`) |
//!
//! Converting to a `Scan<360>` takes another 5776 bytes, on the caller's stack.
//!
//! Frame checks are not enough where they are weak (two check bits per RPLIDAR node: a quarter
//! of random 5-byte windows pass), so each decoder also refuses revolutions that are physically
//! implausible for its device and counts them in [`DecodeStats::implausible`] (limits in each
//! module).

pub mod rplidar;
pub mod scip;
pub mod scip_command;
pub mod xv11;
pub mod xv11_old;
pub mod xv11_revolution;

#[cfg(test)]
mod test_encoders;

/// Counters a decoder keeps about what it saw. One struct for every device so summaries and
/// tests read the same way; a field a device cannot produce stays 0 (documented per field).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecodeStats {
    /// Every byte pushed.
    pub bytes: u64,
    /// Frames (packets, lines, nodes) that passed every check.
    pub packets_ok: u32,
    /// Frames whose checksum (XV-11 packet, SCIP line sum, RPLIDAR check bits) was wrong.
    pub bad_checksum: u32,
    /// Frames well delimited but impossible (bad index, unknown status, torn old-firmware frame).
    pub malformed: u32,
    /// Bytes discarded while searching for a frame start (garbage, wrong baud rate).
    pub skipped_bytes: u64,
    /// Revolutions handed out, complete or not.
    pub revolutions: u32,
    /// XV-11: packets whose index was lower than the one before without being a wrap.
    pub out_of_order: u32,
    /// XV-11: packets absent from the revolutions handed out (each leaves four invalid beams).
    pub missing_packets: u32,
    /// Readings that did not fit the revolution buffer (RPLIDAR, SCIP with too many steps).
    pub overflow: u32,
    /// Revolutions assembled from frames that passed their checks but that the device cannot
    /// have sent (a speed outside its range, too few beams for a turn, angles that jump or sweep
    /// more than a turn, steps beyond the sensor): not handed out. Bytes from another device or
    /// random bytes pass weak frame checks by chance; many of these mean the wrong device.
    pub implausible: u32,
}

/// What every decoder offers, so drivers, tests and fuzzers treat the devices alike.
pub trait ByteDecoder {
    /// What one complete (or, at the end, partial) revolution looks like for this device.
    type Revolution;
    /// Feeds one byte; returns the revolution it closed, if any.
    fn push(&mut self, byte: u8) -> Option<Self::Revolution>;
    /// Ends the stream: whatever is held back that may still be handed out.
    fn finish(&mut self) -> Option<Self::Revolution>;
    fn stats(&self) -> DecodeStats;

    /// Decodes a whole buffer, then ends the stream; revolutions go to `out`.
    fn decode_into<E: Extend<Self::Revolution>>(&mut self, bytes: &[u8], out: &mut E) {
        out.extend(bytes.iter().filter_map(|&b| self.push(b)));
        out.extend(self.finish());
    }
}

/// Implements [`ByteDecoder`] with the type's inherent `push`, `finish` and `stats`.
macro_rules! byte_decoder {
    ($ty:ty, $rev:ty $(, const $n:ident)?) => {
        impl$(<const $n: usize>)? $crate::lidar::ByteDecoder for $ty {
            type Revolution = $rev;
            fn push(&mut self, byte: u8) -> Option<$rev> {
                <$ty>::push(self, byte)
            }
            fn finish(&mut self) -> Option<$rev> {
                <$ty>::finish(self)
            }
            fn stats(&self) -> $crate::lidar::DecodeStats {
                <$ty>::stats(self)
            }
        }
    };
}

byte_decoder!(xv11_revolution::Xv11Decoder, xv11_revolution::Revolution);
byte_decoder!(xv11_old::Xv11OldDecoder, xv11_revolution::Revolution);
byte_decoder!(scip::ScipDecoder<N>, scip::ScipScan<N>, const N);
byte_decoder!(rplidar::RplidarDecoder<N>, rplidar::RplidarRevolution<N>, const N);
