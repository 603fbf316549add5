//! What the view did, counted so that a misbehaving client or a refused command is visible.

use std::sync::atomic::{AtomicU64, Ordering};

/// Counters the server thread bumps; the vehicle's loop reads them with [`Counters::read`].
#[derive(Debug, Default)]
pub(crate) struct Counters {
    pub clients_connected: AtomicU64,
    pub clients_dropped_slow: AtomicU64,
    pub clients_disconnected: AtomicU64,
    pub frames_sent: AtomicU64,
    pub frames_skipped: AtomicU64,
    pub maps_sent: AtomicU64,
    pub commands_accepted: AtomicU64,
    pub commands_refused: AtomicU64,
    pub commands_invalid: AtomicU64,
    pub commands_queue_full: AtomicU64,
}

impl Counters {
    pub fn bump(counter: &AtomicU64) {
        counter.fetch_add(1, Ordering::Relaxed);
    }

    pub fn add(counter: &AtomicU64, n: u64) {
        counter.fetch_add(n, Ordering::Relaxed);
    }

    pub fn read(&self) -> ViewStats {
        let r = |c: &AtomicU64| c.load(Ordering::Relaxed);
        ViewStats {
            clients_connected: r(&self.clients_connected),
            clients_dropped_slow: r(&self.clients_dropped_slow),
            clients_disconnected: r(&self.clients_disconnected),
            frames_sent: r(&self.frames_sent),
            frames_skipped: r(&self.frames_skipped),
            maps_sent: r(&self.maps_sent),
            commands_accepted: r(&self.commands_accepted),
            commands_refused: r(&self.commands_refused),
            commands_invalid: r(&self.commands_invalid),
            commands_queue_full: r(&self.commands_queue_full),
        }
    }
}

impl ViewStats {
    /// Clients still connected.
    pub fn clients_open(&self) -> u64 {
        self.clients_connected
            .saturating_sub(self.clients_dropped_slow + self.clients_disconnected)
    }
}

/// What the view has done since it started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct ViewStats {
    /// Websocket clients that connected.
    pub clients_connected: u64,
    /// Clients dropped because their socket would not take a message within the send timeout
    /// (a client that never reads).
    pub clients_dropped_slow: u64,
    /// Clients that closed or vanished.
    pub clients_disconnected: u64,
    /// State frames sent, over all clients.
    pub frames_sent: u64,
    /// Frames a client never got because a newer one replaced it while it was busy.
    pub frames_skipped: u64,
    /// Map images sent, over all clients.
    pub maps_sent: u64,
    /// Commands handed to the vehicle's loop.
    pub commands_accepted: u64,
    /// Commands refused: read-only view, or a missing or wrong token (HTTP 403).
    pub commands_refused: u64,
    /// Commands with the right token but no known name (HTTP 400).
    pub commands_invalid: u64,
    /// Commands refused because the vehicle's loop had not taken the earlier ones (HTTP 503).
    pub commands_queue_full: u64,
}
