//! A live web view of a flight: one static page compiled into the binary and a websocket that
//! streams the vehicle's state (map, current scan, pose and trail, battery, mode, failsafe) at
//! no more than 20 Hz.
//!
//! The server runs on its own thread with its own single-threaded runtime. The vehicle's loop
//! only ever calls [`View::publish`] (replaces the latest snapshot, never waits) and
//! [`View::try_command`] (takes a queued command, never waits), so a slow browser, a client
//! that never reads or one that vanishes mid-stream costs the loop nothing: such a client is
//! dropped or skipped and counted in [`ViewStats`].
//!
//! Read-only unless a token is configured; then `POST /command` with the token in the
//! `X-Plumbline-Token` header turns `arm`, `land` or `kill` into a [`GroundCommand`] for the
//! vehicle's loop. Anything else is refused with HTTP 403 and counted.

mod clients;
mod command;
mod encode;
mod page;
mod scan_map;
mod snapshot;
mod stats;
mod ticker;

pub use scan_map::{scan_points, ScanMap};
pub use snapshot::{OccupancyImage, Snapshot, FREE, OCCUPIED, UNKNOWN};
pub use stats::ViewStats;

use plumbline_core::msgs::GroundCommand;
use stats::Counters;
use std::net::SocketAddr;
use std::sync::mpsc::{sync_channel, Receiver};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;
use tokio::sync::{oneshot, watch};

/// The fastest state stream the page gets, Hz.
pub const MAX_FRAME_HZ: f64 = 20.0;
/// Commands waiting for the vehicle's loop; more are refused (HTTP 503) until it takes them.
pub const COMMAND_QUEUE: usize = 16;

/// How the view serves.
#[derive(Clone, Debug)]
pub struct ViewConfig {
    /// Where to listen; keep it on loopback (127.0.0.1) unless others must watch.
    pub addr: SocketAddr,
    /// With a token the page offers arm/land/kill, and commands carrying it are accepted.
    pub token: Option<String>,
    /// State frames per second to each client, at most [`MAX_FRAME_HZ`].
    pub frame_hz: f64,
    /// Map images per second at most (a map is sent only when it changed).
    pub map_hz: f64,
    /// A client whose socket takes longer than this to accept one message is dropped.
    pub send_timeout: Duration,
}

impl ViewConfig {
    /// Serve on `addr` at the full frame rate, maps at 2 Hz, dropping clients stuck for 2 s.
    pub fn new(addr: SocketAddr, token: Option<String>) -> Self {
        Self {
            addr,
            token,
            frame_hz: MAX_FRAME_HZ,
            map_hz: 2.0,
            send_timeout: Duration::from_secs(2),
        }
    }
}

/// Why the view could not start.
#[derive(Debug)]
pub enum ViewError {
    /// A setting is out of range; the message says which and what is allowed.
    Config(String),
    /// The address could not be bound (in use, not a local address, no permission).
    Bind(SocketAddr, std::io::Error),
    /// The server thread or its runtime could not be started.
    Start(std::io::Error),
}

impl std::fmt::Display for ViewError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Config(m) => write!(f, "web view: {m}"),
            Self::Bind(a, e) => write!(
                f,
                "web view: cannot listen on {a}: {e} (pick another port, e.g. 127.0.0.1:0 for any free one)"
            ),
            Self::Start(e) => write!(f, "web view: cannot start the server thread: {e}"),
        }
    }
}

impl std::error::Error for ViewError {}

/// The running view, owned by the vehicle's loop. Dropping it stops the server.
pub struct View {
    addr: SocketAddr,
    latest: watch::Sender<Arc<Snapshot>>,
    commands: Receiver<GroundCommand>,
    counters: Arc<Counters>,
    shutdown: Option<oneshot::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl View {
    /// Binds `config.addr` (so a busy port is reported before the flight starts) and starts
    /// the server thread.
    pub fn start(config: ViewConfig) -> Result<Self, ViewError> {
        check(&config)?;
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_io()
            .enable_time()
            .build()
            .map_err(ViewError::Start)?;
        let listener = runtime
            .block_on(tokio::net::TcpListener::bind(config.addr))
            .map_err(|e| ViewError::Bind(config.addr, e))?;
        let addr = listener
            .local_addr()
            .map_err(|e| ViewError::Bind(config.addr, e))?;
        let (latest, snapshots) = watch::channel(Arc::new(Snapshot::default()));
        let (command_tx, commands) = sync_channel(COMMAND_QUEUE);
        let counters = Arc::new(Counters::default());
        let (shutdown, stop) = oneshot::channel();
        let server = clients::Server::new(config, snapshots, command_tx, counters.clone());
        let thread = std::thread::Builder::new()
            .name("plumbline-view".into())
            .spawn(move || runtime.block_on(server.serve(listener, stop)))
            .map_err(ViewError::Start)?;
        Ok(Self {
            addr,
            latest,
            commands,
            counters,
            shutdown: Some(shutdown),
            thread: Some(thread),
        })
    }

    /// The address the view listens on (the real port when 0 was asked for).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Makes `snapshot` the state the page shows next; replaces any not yet sent. Never waits.
    pub fn publish(&self, snapshot: Snapshot) {
        self.latest.send_replace(Arc::new(snapshot));
    }

    /// The oldest accepted command not yet taken, if any. Never waits.
    pub fn try_command(&self) -> Option<GroundCommand> {
        self.commands.try_recv().ok()
    }

    /// What the view has done so far.
    pub fn stats(&self) -> ViewStats {
        self.counters.read()
    }
}

impl Drop for View {
    fn drop(&mut self) {
        if let Some(s) = self.shutdown.take() {
            let _ = s.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn check(c: &ViewConfig) -> Result<(), ViewError> {
    if !(c.frame_hz > 0.0 && c.frame_hz <= MAX_FRAME_HZ) {
        return Err(ViewError::Config(format!(
            "frame rate {} Hz is outside (0, {MAX_FRAME_HZ}]",
            c.frame_hz
        )));
    }
    if !(c.map_hz > 0.0 && c.map_hz <= c.frame_hz) {
        return Err(ViewError::Config(format!(
            "map rate {} Hz is outside (0, frame rate {}]",
            c.map_hz, c.frame_hz
        )));
    }
    if c.send_timeout.is_zero() {
        return Err(ViewError::Config("send timeout must be positive".into()));
    }
    if let Some(t) = &c.token {
        if t.is_empty() || !t.bytes().all(|b| b.is_ascii_graphic()) {
            return Err(ViewError::Config(
                "the token must be non-empty printable ASCII without spaces".into(),
            ));
        }
    }
    Ok(())
}
