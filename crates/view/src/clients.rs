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
use crate::ticker::{Frame, Ticker};
use crate::ViewConfig;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{DefaultBodyLimit, State};
use axum::http::{header, HeaderMap, StatusCode};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use axum::Router;
use plumbline_core::msgs::GroundCommand;
use std::sync::mpsc::SyncSender;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::{oneshot, watch};
use tokio::time::timeout;

/// A trail point is added once the vehicle has moved this far from the last one, m.
const TRAIL_STEP_M: f32 = 0.05;
/// The trail keeps at most this many points; when full, every other point is dropped, so the
/// whole flight stays on the page at a coarser spacing.
const TRAIL_POINTS: usize = 4000;
/// How long the last frame is given to reach the clients when the view stops.
const FINAL_FLUSH: Duration = Duration::from_millis(300);
/// Longest command body taken, bytes: the longest command name with room for a newline.
const COMMAND_BODY_LIMIT: usize = 64;

/// The flight's path so far as flat x, y pairs, thinned as described at [`TRAIL_POINTS`].
#[derive(Default)]
pub(crate) struct Trail {
    points_m: Vec<f32>,
}

impl Trail {
    pub fn push(&mut self, x: f32, y: f32) {
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
pub(crate) struct Shared {
    token: Option<String>,
    frames: watch::Receiver<Arc<Frame>>,
    pub trail: Mutex<Trail>,
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
        let mut ticker = Ticker::new(self.snapshots, frames_tx, shared.clone(), &self.config);
        let app = Router::new()
            .route("/", get(index))
            .route("/ws", get(upgrade))
            .route("/command", post(command))
            .route("/stats", get(stats))
            .layer(DefaultBodyLimit::max(COMMAND_BODY_LIMIT))
            .with_state(shared.clone());
        tokio::select! {
            _ = axum::serve(listener, app) => {}
            _ = ticker.run() => {}
            _ = stop => {}
        }
        // The flight is over: its last state and map go out before the clients are closed.
        ticker.frame(true);
        if shared.counters.read().clients_open() > 0 {
            tokio::time::sleep(FINAL_FLUSH.min(shared.send_timeout)).await;
        }
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
