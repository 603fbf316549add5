//! What the inbound side dropped, by reason, so a flight log or a test can say why a command
//! did not arrive.

/// Counts of refused input since the link started. Every byte or frame that does not become
/// an event is counted in exactly one of these (a frame's bytes are not also counted as
/// skipped, except the one byte a rejected candidate is retried after).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DropCounters {
    /// Bytes that started no frame (garbage, or the first byte of a rejected candidate).
    pub skipped_bytes: u64,
    /// Candidates of a known message whose checksum did not match.
    pub bad_crc: u64,
    /// Candidates of a message id the common dialect does not define.
    pub unknown_id: u64,
    /// MAVLink 2 candidates with incompatibility flags this link does not implement.
    pub bad_header: u64,
    /// Good frames whose payload does not make a valid message (an enum out of range, an
    /// invalid stick axis).
    pub malformed: u64,
    /// Messages addressed to another system or component.
    pub other_target: u64,
    /// State-changing messages (COMMAND_LONG, MANUAL_CONTROL, PARAM_SET) and ground-station
    /// HEARTBEATs that were not signed while a key is set.
    pub unsigned: u64,
    /// Signed frames whose signature does not match the key.
    pub bad_signature: u64,
    /// Signed frames with a timestamp already seen on their stream, or too old for a new one.
    pub replayed: u64,
    /// PARAM_SET beyond the allowed rate.
    pub rate_limited: u64,
    /// Good messages this link has no use for (other vehicles' telemetry, unsupported
    /// services). Not an error; counted so nothing disappears silently.
    pub not_handled: u64,
}

impl DropCounters {
    /// Refusals of the kinds that mean something is wrong with the link or its peer (every
    /// counter except `skipped_bytes` and `not_handled`).
    pub fn refused(&self) -> u64 {
        self.bad_crc
            + self.unknown_id
            + self.bad_header
            + self.malformed
            + self.other_target
            + self.unsigned
            + self.bad_signature
            + self.replayed
            + self.rate_limited
    }
}
