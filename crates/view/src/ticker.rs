//! The ticker: turns the newest snapshot into one frame for every client at the frame rate,
//! and the map into a PNG when it changed, at most at the map rate. Encoding happens once per
//! frame, whatever the number of clients.

use crate::clients::Shared;
use crate::encode;
use crate::snapshot::Snapshot;
use crate::ViewConfig;
use axum::body::Bytes;
use axum::extract::ws::Utf8Bytes;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::watch;
use tokio::time::{interval, MissedTickBehavior};

/// The map as sent: its version, geometry message and PNG.
pub(crate) struct EncodedMap {
    pub version: u64,
    pub meta: Utf8Bytes,
    pub png: Bytes,
}

/// What the ticker hands every client: the state message and the newest map.
#[derive(Default)]
pub(crate) struct Frame {
    pub seq: u64,
    pub state: Utf8Bytes,
    pub map: Option<Arc<EncodedMap>>,
}

pub(crate) struct Ticker {
    snapshots: watch::Receiver<Arc<Snapshot>>,
    frames: watch::Sender<Arc<Frame>>,
    shared: Arc<Shared>,
    frame_every: Duration,
    map_every: Duration,
    map: Option<Arc<EncodedMap>>,
    map_at: Option<Instant>,
    seq: u64,
}

impl Ticker {
    pub fn new(
        snapshots: watch::Receiver<Arc<Snapshot>>,
        frames: watch::Sender<Arc<Frame>>,
        shared: Arc<Shared>,
        config: &ViewConfig,
    ) -> Self {
        Self {
            snapshots,
            frames,
            shared,
            frame_every: Duration::from_secs_f64(1.0 / config.frame_hz),
            map_every: Duration::from_secs_f64(1.0 / config.map_hz),
            map: None,
            map_at: None,
            seq: 0,
        }
    }

    /// Frames at the frame rate until the vehicle's side is gone.
    pub async fn run(&mut self) {
        let mut every = interval(self.frame_every);
        every.set_missed_tick_behavior(MissedTickBehavior::Skip);
        loop {
            every.tick().await;
            if !self.frame(false) {
                return;
            }
        }
    }

    /// Publishes a frame if a new snapshot came; `final_map` sends a changed map even before
    /// the map rate allows. False once the vehicle's side is gone.
    pub fn frame(&mut self, final_map: bool) -> bool {
        match self.snapshots.has_changed() {
            Ok(true) => {}
            Ok(false) => return true,
            Err(_) => return false,
        }
        let snap = self.snapshots.borrow_and_update().clone();
        self.seq += 1;
        if let Ok(mut trail) = self.shared.trail.lock() {
            trail.push(snap.pose[0] as f32, snap.pose[1] as f32);
        }
        let due = final_map || self.map_at.is_none_or(|t| t.elapsed() >= self.map_every);
        if let Some(image) = snap.map.as_deref().filter(|_| due) {
            if self.map.as_ref().is_none_or(|m| m.version != image.version) {
                if let Some((meta, png)) = encode::map(image) {
                    self.map = Some(Arc::new(EncodedMap {
                        version: image.version,
                        meta: meta.into(),
                        png: png.into(),
                    }));
                    self.map_at = Some(Instant::now());
                }
            }
        }
        self.frames.send_replace(Arc::new(Frame {
            seq: self.seq,
            state: encode::state(self.seq, &snap).into(),
            map: self.map.clone(),
        }));
        true
    }
}
