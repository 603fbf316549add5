//! The server thread's work: one ticker that turns the latest snapshot into messages at the
//! frame rate, and one task per websocket client that sends the newest frame it has not sent.
//!
//! Frames reach the client tasks through a latest-wins channel, so a client that is slow only
//! misses frames (counted as skipped); one whose socket does not take a message within the send
//! timeout is dropped (counted). Nothing a client does reaches the ticker or the vehicle's loop.

use crate::command;
use crate::encode;
use crate::page::INDEX_HTML;
use crate::snapshot::Snapshot;
use crate::stats::Counters;
use crate::ViewConfig;
use axum::body::Bytes;
use axum::extract::ws::{Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::extract::{DefaultBodyLimit, State};
use axum::http::{header, HeaderMap, StatusCode};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use axum::Router;
use plumbline_core::msgs::GroundCommand;
use std::sync::mpsc::SyncSender;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::{oneshot, watch};
use tokio::time::{interval, timeout, MissedTickBehavior};

/// A trail point is added once the vehicle has moved this far from the last one, m.
const TRAIL_STEP_M: f32 = 0.05;
/// The trail keeps at most this many points; when full, every other point is dropped, so the
/// whole flight stays on the page at a coarser spacing.
const TRAIL_POINTS: usize = 4000;
/// Longest command body taken, bytes: the longest command name with room for a newline.
const COMMAND_BODY_LIMIT: usize = 64;

/// The map as sent: its version, geometry message and PNG.
struct EncodedMap {
    version: u64,
    meta: Utf8Bytes,
    png: Bytes,
}

/// What the ticker hands every client: the state message and the newest map.
#[derive(Default)]
struct Frame {
    seq: u64,
    state: Utf8Bytes,
    map: Option<Arc<EncodedMap>>,
}

/// The flight's path so far as flat x, y pairs, thinned as described at [`TRAIL_POINTS`].
#[derive(Default)]
struct Trail {
    points_m: Vec<f32>,
}

impl Trail {
    fn push(&mut self, x: f32, y: f32) {
        if !(x.is_finite() && y.is_finite()) {
            return;
        }
        if let [.., lx, ly] = self.points_m[..] {
            if (x - lx).hypot(y - ly) < TRAIL_STEP_M {
                return;
            }
        }
        if self.points_m.len() >= 2 * TRAIL_POINTS {
            let thinned: Vec<f32> = self
                .points_m
                .chunks_exact(4)
                .flat_map(|c| [c[0], c[1]])
                .collect();
            self.points_m = thinned;
        }
        self.points_m.extend([x, y]);
    }
}

/// What every request handler and client task shares.
struct Shared {
    token: Option<String>,
    frames: watch::Receiver<Arc<Frame>>,
    trail: Mutex<Trail>,
    commands: SyncSender<GroundCommand>,
    counters: Arc<Counters>,
    send_timeout: Duration,
}

/// The server as built on the vehicle's thread and moved onto its own.
pub(crate) struct Server {
    config: ViewConfig,
    snapshots: watch::Receiver<Arc<Snapshot>>,
    commands: SyncSender<GroundCommand>,
    counters: Arc<Counters>,
}

impl Server {
    pub fn new(
        config: ViewConfig,
        snapshots: watch::Receiver<Arc<Snapshot>>,
        commands: SyncSender<GroundCommand>,
        counters: Arc<Counters>,
    ) -> Self {
        Self {
            config,
            snapshots,
            commands,
            counters,
        }
    }

    /// Serves until `stop` fires (or the view is dropped); open client tasks end with the
    /// runtime.
    pub async fn serve(self, listener: tokio::net::TcpListener, stop: oneshot::Receiver<()>) {
        let (frames_tx, frames) = watch::channel(Arc::new(Frame::default()));
        let shared = Arc::new(Shared {
            token: self.config.token.clone(),
            frames,
            trail: Mutex::new(Trail::default()),
            commands: self.commands,
            counters: self.counters,
            send_timeout: self.config.send_timeout,
        });
        let ticker = tick(self.snapshots, frames_tx, shared.clone(), &self.config);
        let app = Router::new()
            .route("/", get(index))
            .route("/ws", get(upgrade))
            .route("/command", post(command))
            .route("/stats", get(stats))
            .layer(DefaultBodyLimit::max(COMMAND_BODY_LIMIT))
            .with_state(shared);
        tokio::select! {
            _ = axum::serve(listener, app) => {}
            _ = ticker => {}
            _ = stop => {}
        }
    }
}

/// Turns the newest snapshot into a frame at the frame rate, and the map into a PNG when it
/// changed, at most at the map rate.
async fn tick(
    mut snapshots: watch::Receiver<Arc<Snapshot>>,
    frames: watch::Sender<Arc<Frame>>,
    shared: Arc<Shared>,
    config: &ViewConfig,
) {
    let mut every = interval(Duration::from_secs_f64(1.0 / config.frame_hz));
    every.set_missed_tick_behavior(MissedTickBehavior::Skip);
    let map_every = Duration::from_secs_f64(1.0 / config.map_hz);
    let mut map: Option<Arc<EncodedMap>> = None;
    let mut map_at: Option<Instant> = None;
    let mut seq = 0;
    loop {
        every.tick().await;
        match snapshots.has_changed() {
            Ok(true) => {}
            Ok(false) => continue,
            Err(_) => return,
        }
        let snap = snapshots.borrow_and_update().clone();
        seq += 1;
        if let Ok(mut trail) = shared.trail.lock() {
            trail.push(snap.pose[0] as f32, snap.pose[1] as f32);
        }
        let due = map_at.is_none_or(|t| t.elapsed() >= map_every);
        let newer = |m: &Arc<EncodedMap>, v| m.version != v;
        if let Some(image) = snap.map.as_deref().filter(|_| due) {
            if map.as_ref().is_none_or(|m| newer(m, image.version)) {
                if let Some((meta, png)) = encode::map(image) {
                    map = Some(Arc::new(EncodedMap {
                        version: image.version,
                        meta: meta.into(),
                        png: png.into(),
                    }));
                    map_at = Some(Instant::now());
                }
            }
        }
        frames.send_replace(Arc::new(Frame {
            seq,
            state: encode::state(seq, &snap).into(),
            map: map.clone(),
        }));
    }
}

async fn index() -> Response {
    ([(header::CACHE_CONTROL, "no-store")], Html(INDEX_HTML)).into_response()
}

async fn stats(State(shared): State<Arc<Shared>>) -> Response {
    let text = serde_json::to_string(&shared.counters.read()).unwrap_or_default();
    ([(header::CONTENT_TYPE, "application/json")], text).into_response()
}

async fn command(
    State(shared): State<Arc<Shared>>,
    headers: HeaderMap,
    body: String,
) -> (StatusCode, String) {
    command::handle(
        shared.token.as_deref(),
        &headers,
        &body,
        &shared.commands,
        &shared.counters,
    )
}

async fn upgrade(State(shared): State<Arc<Shared>>, ws: WebSocketUpgrade) -> Response {
    ws.on_upgrade(move |socket| client(socket, shared))
}

/// Why a client's stream ended.
enum Gone {
    /// Its socket would not take a message within the send timeout.
    Stuck,
    /// It closed or the connection broke.
    Left,
}

async fn send(socket: &mut WebSocket, msg: Message, within: Duration) -> Result<(), Gone> {
    match timeout(within, socket.send(msg)).await {
        Ok(Ok(())) => Ok(()),
        Ok(Err(_)) => Err(Gone::Left),
        Err(_) => Err(Gone::Stuck),
    }
}

async fn client(mut socket: WebSocket, shared: Arc<Shared>) {
    let c = &shared.counters;
    Counters::bump(&c.clients_connected);
    let gone = stream(&mut socket, &shared).await;
    match gone {
        Gone::Stuck => Counters::bump(&c.clients_dropped_slow),
        Gone::Left => Counters::bump(&c.clients_disconnected),
    }
}

/// Sends the hello, then each newest frame (the map first when it is new to this client),
/// until the client leaves or gets stuck. Messages from the client are read only to notice
/// that it left: commands go through `POST /command`.
async fn stream(socket: &mut WebSocket, shared: &Shared) -> Gone {
    let (c, within) = (&shared.counters, shared.send_timeout);
    let hello = match shared.trail.lock() {
        Ok(t) => encode::hello(shared.token.is_some(), &t.points_m),
        Err(_) => encode::hello(shared.token.is_some(), &[]),
    };
    if let Err(g) = send(socket, Message::Text(hello.into()), within).await {
        return g;
    }
    let mut frames = shared.frames.clone();
    let (mut last_seq, mut map_version) = (None, None);
    loop {
        tokio::select! {
            changed = frames.changed() => {
                if changed.is_err() {
                    return Gone::Left;
                }
                let frame = frames.borrow_and_update().clone();
                if let Some(last) = last_seq {
                    Counters::add(&c.frames_skipped, frame.seq.saturating_sub(last + 1));
                }
                last_seq = Some(frame.seq);
                if let Some(m) = frame.map.as_ref().filter(|m| map_version != Some(m.version)) {
                    if let Err(g) = send(socket, Message::Text(m.meta.clone()), within).await {
                        return g;
                    }
                    if let Err(g) = send(socket, Message::Binary(m.png.clone()), within).await {
                        return g;
                    }
                    map_version = Some(m.version);
                    Counters::bump(&c.maps_sent);
                }
                if let Err(g) = send(socket, Message::Text(frame.state.clone()), within).await {
                    return g;
                }
                Counters::bump(&c.frames_sent);
            }
            incoming = socket.recv() => match incoming {
                None | Some(Err(_)) | Some(Ok(Message::Close(_))) => return Gone::Left,
                Some(Ok(_)) => {}
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_trail_thins_instead_of_growing_without_bound() {
        let mut t = Trail::default();
        t.push(0.0, 0.0);
        t.push(0.01, 0.0);
        assert_eq!(t.points_m.len(), 2, "moves under the step are not kept");
        t.push(f32::NAN, 0.0);
        assert_eq!(t.points_m.len(), 2);
        for k in 1..=3 * TRAIL_POINTS {
            t.push(k as f32 * 0.1, 0.0);
        }
        assert!(t.points_m.len() <= 2 * TRAIL_POINTS);
        assert_eq!(t.points_m[..2], [0.0, 0.0], "the start stays");
        let last = t.points_m[t.points_m.len() - 2];
        assert!(
            (last - 3.0 * TRAIL_POINTS as f32 * 0.1).abs() < 1e-3,
            "the newest stays"
        );
    }
}
