//! MAVLink 2 message signing (<https://mavlink.io/en/guide/message_signing.html>) with the time
//! passed in, so the link reads no clock and a test or fuzzer replays it exactly.
//!
//! The signature itself is the `mavlink` crate's (SHA-256 over key, frame and trailer); this
//! module owns the timestamps: outgoing ones strictly increase, and an incoming signed frame is
//! accepted only when its timestamp is newer than the last one accepted on its stream
//! (link id, system, component) or, for a stream not seen before, no more than a minute older
//! than the local time (the newer of the caller's clock and every timestamp accepted so far).

use mavlink::MAVLinkV2MessageRaw;

/// Seconds from the Unix epoch to 2015-01-01 00:00 UTC, where signing timestamps start.
const SIGNING_EPOCH_UNIX_S: f64 = 1_420_070_400.0;
/// Signing timestamps count 10 microseconds.
const TICKS_PER_S: f64 = 100_000.0;
/// They are 48 bits wide.
const TIMESTAMP_MASK: u64 = (1 << 48) - 1;
/// How much older than the local time a new stream's first timestamp may be (one minute).
const NEW_STREAM_WINDOW_TICKS: u64 = 60 * 100_000;
/// Streams remembered for replay protection. A ground station, a companion and a spare; when
/// full the stream heard from longest ago is forgotten (its next frame is then judged as a new
/// stream's, against the one-minute window).
const MAX_STREAMS: usize = 8;

/// A 32-byte signing key and the link id this end signs with.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct SigningKey {
    pub secret: [u8; 32],
    pub link_id: u8,
}

impl core::fmt::Debug for SigningKey {
    // The secret never reaches a log.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SigningKey")
            .field("link_id", &self.link_id)
            .finish_non_exhaustive()
    }
}

/// Why a signed frame was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SignatureFault {
    /// The signature does not match the key.
    Bad,
    /// The timestamp is not newer than the stream's last, or a new stream's is too old.
    Replayed,
}

#[derive(Clone, Copy, Debug)]
struct Stream {
    link_id: u8,
    system_id: u32,
    component_id: u8,
    last_timestamp: u64,
}

/// Signing state of one link end.
#[derive(Clone, Debug)]
pub(crate) struct Signer {
    key: SigningKey,
    /// The newest of the caller's clock, every accepted timestamp and every sent one.
    local_timestamp: u64,
    last_sent: Option<u64>,
    streams: Vec<Stream>,
}

/// A signing timestamp from Unix time in seconds (0 before 2015, as the spec's clockless start).
pub fn timestamp_from_unix(unix_s: f64) -> u64 {
    let ticks = (unix_s - SIGNING_EPOCH_UNIX_S) * TICKS_PER_S;
    if ticks.is_finite() && ticks > 0.0 {
        (ticks as u64) & TIMESTAMP_MASK
    } else {
        0
    }
}

impl Signer {
    pub(crate) fn new(key: SigningKey) -> Self {
        Self {
            key,
            local_timestamp: 0,
            last_sent: None,
            streams: Vec::with_capacity(MAX_STREAMS),
        }
    }

    fn advance_clock(&mut self, unix_s: f64) {
        self.local_timestamp = self.local_timestamp.max(timestamp_from_unix(unix_s));
    }

    /// Fills the signature trailer of a frame serialized with the signed flag set.
    pub(crate) fn sign(&mut self, raw: &mut MAVLinkV2MessageRaw, unix_s: f64) {
        self.advance_clock(unix_s);
        let timestamp = match self.last_sent {
            Some(last) if last >= self.local_timestamp => last + 1,
            _ => self.local_timestamp,
        };
        self.last_sent = Some(timestamp);
        self.local_timestamp = self.local_timestamp.max(timestamp);
        raw.signature_timestamp_bytes_mut()
            .copy_from_slice(&timestamp.to_le_bytes()[..6]);
        *raw.signature_link_id_mut() = self.key.link_id;
        let mut signature = [0u8; 6];
        raw.calculate_signature(&self.key.secret, &mut signature);
        raw.signature_value_mut().copy_from_slice(&signature);
    }

    /// Checks a signed frame's signature and timestamp; remembers the timestamp if accepted.
    pub(crate) fn verify(
        &mut self,
        raw: &MAVLinkV2MessageRaw,
        unix_s: f64,
    ) -> Result<(), SignatureFault> {
        let mut expected = [0u8; 6];
        raw.calculate_signature(&self.key.secret, &mut expected);
        if expected != raw.signature_value() {
            return Err(SignatureFault::Bad);
        }
        self.advance_clock(unix_s);
        let timestamp = raw.signature_timestamp();
        let (link_id, system_id, component_id) =
            (raw.signature_link_id(), raw.system_id(), raw.component_id());
        let known = self.streams.iter().position(|s| {
            s.link_id == link_id && s.system_id == system_id && s.component_id == component_id
        });
        match known {
            Some(i) if timestamp <= self.streams[i].last_timestamp => {
                return Err(SignatureFault::Replayed)
            }
            None if timestamp + NEW_STREAM_WINDOW_TICKS < self.local_timestamp => {
                return Err(SignatureFault::Replayed)
            }
            _ => {}
        }
        let stream = Stream {
            link_id,
            system_id,
            component_id,
            last_timestamp: timestamp,
        };
        match known {
            Some(i) => self.streams[i] = stream,
            None if self.streams.len() < MAX_STREAMS => self.streams.push(stream),
            None => {
                let oldest = (0..self.streams.len())
                    .min_by_key(|&i| self.streams[i].last_timestamp)
                    .unwrap_or(0);
                self.streams[oldest] = stream;
            }
        }
        self.local_timestamp = self.local_timestamp.max(timestamp);
        Ok(())
    }
}
