//! The view served on loopback with a synthetic feed: the page, the stream, commands and their
//! token, and clients that misbehave.

use plumbline_core::msgs::{FlightMode, GroundCommand};
use plumbline_view::{OccupancyImage, Snapshot, View, ViewConfig, ViewStats, FREE, OCCUPIED};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tungstenite::Message;

/// Upper bound on any wait in these tests; they normally take a fraction of it.
const PATIENCE: Duration = Duration::from_secs(20);

fn start(token: Option<&str>) -> View {
    let mut config = ViewConfig::new("127.0.0.1:0".parse().unwrap(), token.map(String::from));
    config.send_timeout = Duration::from_millis(500);
    View::start(config).expect("view starts")
}

fn snapshot(t_s: f64, map: Option<Arc<OccupancyImage>>) -> Snapshot {
    Snapshot {
        t_s,
        pose: [t_s, 1.0, 1.2, 0.5],
        estimate_valid: true,
        scan_m: vec![[3.0, 1.0], [t_s as f32, 4.0]],
        battery_v: Some(11.9),
        mode: Some(FlightMode::Hold),
        failsafe: None,
        map,
    }
}

/// One HTTP/1.1 request; the status code and body.
fn http(addr: SocketAddr, request: &str) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(PATIENCE)).unwrap();
    s.write_all(request.as_bytes()).unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let status = text[9..12].parse().unwrap();
    let body = text.split_once("\r\n\r\n").map_or("", |p| p.1).to_string();
    (status, body)
}

fn post(addr: SocketAddr, token: Option<&str>, body: &str) -> u16 {
    let header = token.map_or(String::new(), |t| format!("X-Plumbline-Token: {t}\r\n"));
    let req = format!(
        "POST /command HTTP/1.1\r\nHost: x\r\nConnection: close\r\n{header}Content-Length: {}\r\n\r\n{body}",
        body.len()
    );
    http(addr, &req).0
}

/// Waits until `done` holds for the view's counters, publishing with `feed` meanwhile.
fn wait_for(
    view: &View,
    mut feed: impl FnMut(&View),
    done: impl Fn(&ViewStats) -> bool,
) -> ViewStats {
    let start = Instant::now();
    loop {
        feed(view);
        let s = view.stats();
        if done(&s) {
            return s;
        }
        assert!(start.elapsed() < PATIENCE, "gave up waiting: {s:?}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

type Client = tungstenite::WebSocket<TcpStream>;

fn connect(addr: SocketAddr) -> Client {
    let stream = TcpStream::connect(addr).unwrap();
    stream.set_read_timeout(Some(PATIENCE)).unwrap();
    tungstenite::client(format!("ws://{addr}/ws"), stream)
        .unwrap()
        .0
}

fn next_text(ws: &mut Client) -> serde_json::Value {
    loop {
        if let Message::Text(t) = ws.read().unwrap() {
            return serde_json::from_str(&t).unwrap();
        }
    }
}

#[test]
fn the_page_is_served_from_the_binary() {
    let view = start(None);
    let (status, body) = http(
        view.local_addr(),
        "GET / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n",
    );
    assert_eq!(status, 200);
    assert!(body.contains("<canvas id=\"map\">") && body.contains("new WebSocket"));
    assert!(
        !body.contains("http://") && !body.contains("https://"),
        "nothing from elsewhere"
    );
}

#[test]
fn the_stream_carries_the_map_once_and_the_state_as_it_changes() {
    let view = start(None);
    let map = Arc::new(OccupancyImage {
        version: 1,
        origin_m: [-2.0, -1.0],
        resolution_m: 0.1,
        width: 40,
        height: 20,
        cells: (0..800)
            .map(|i| if i % 40 == 0 { OCCUPIED } else { FREE })
            .collect(),
    });
    view.publish(snapshot(1.0, Some(map.clone())));
    let mut ws = connect(view.local_addr());
    let hello = next_text(&mut ws);
    assert_eq!(hello["type"], "hello");
    assert_eq!(hello["controls"], false);
    let meta = next_text(&mut ws);
    assert_eq!(
        (meta["type"].as_str(), meta["width"].as_u64()),
        (Some("map"), Some(40))
    );
    let Message::Binary(png) = ws.read().unwrap() else {
        panic!("the map's PNG follows its geometry")
    };
    assert_eq!(&png[1..4], b"PNG");
    let first = next_text(&mut ws);
    assert_eq!(
        (first["type"].as_str(), first["mode"].as_str()),
        (Some("state"), Some("hold"))
    );
    assert_eq!(first["scan_cm"], serde_json::json!([300, 100, 100, 400]));
    // A new state with the same map: the state comes, the map does not again.
    view.publish(snapshot(2.0, Some(map)));
    let second = next_text(&mut ws);
    assert_eq!(second["type"], "state");
    assert_eq!(second["t_s"], 2.0);
    assert!(second["seq"].as_u64() > first["seq"].as_u64());
    drop(ws);
    let s = wait_for(&view, |_| {}, |s| s.clients_disconnected == 1);
    assert_eq!((s.clients_connected, s.maps_sent), (1, 1));
}

#[test]
fn a_read_only_view_refuses_every_command() {
    let view = start(None);
    let addr = view.local_addr();
    assert_eq!(post(addr, None, "kill"), 403);
    assert_eq!(post(addr, Some("anything"), "kill"), 403);
    assert_eq!(view.try_command(), None);
    assert_eq!(view.stats().commands_refused, 2);
}

#[test]
fn commands_need_the_token() {
    let view = start(Some("hunter2"));
    let addr = view.local_addr();
    assert_eq!(post(addr, None, "kill"), 403);
    assert_eq!(post(addr, Some("hunter3"), "kill"), 403);
    assert_eq!(post(addr, Some("hunter2"), "fly-away"), 400);
    assert_eq!(view.try_command(), None);
    assert_eq!(post(addr, Some("hunter2"), "kill"), 202);
    assert_eq!(post(addr, Some("hunter2"), "land"), 202);
    assert_eq!(view.try_command(), Some(GroundCommand::Terminate));
    assert_eq!(view.try_command(), Some(GroundCommand::Land));
    let s = view.stats();
    assert_eq!(
        (s.commands_refused, s.commands_invalid, s.commands_accepted),
        (2, 1, 2)
    );
    let mut ws = connect(addr);
    assert_eq!(next_text(&mut ws)["controls"], true);
}

/// A map of noise: a PNG as large as its cells, so that a client that never reads fills its
/// socket quickly.
fn noise_map(version: u64) -> Arc<OccupancyImage> {
    let mut x = version.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let cells = (0..500 * 500)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect();
    Arc::new(OccupancyImage {
        version,
        origin_m: [0.0, 0.0],
        resolution_m: 0.05,
        width: 500,
        height: 500,
        cells,
    })
}

#[test]
fn a_client_that_never_reads_is_dropped_and_the_others_go_on() {
    let view = start(None);
    let addr = view.local_addr();
    // Handshake by hand, then never read a byte.
    let mut stuck = TcpStream::connect(addr).unwrap();
    stuck
        .write_all(
            b"GET /ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
              Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n",
        )
        .unwrap();
    let version = std::cell::Cell::new(0);
    let mut feed = |v: &View| {
        version.set(version.get() + 1);
        v.publish(snapshot(
            version.get() as f64,
            Some(noise_map(version.get())),
        ));
    };
    wait_for(&view, &mut feed, |s| s.clients_connected == 1);
    // A client that keeps reading, on its own thread: the newest time it saw.
    let seen = Arc::new(std::sync::Mutex::new(0.0));
    let mut reader = connect(addr);
    let seen_by_reader = seen.clone();
    let reading = std::thread::spawn(move || {
        while let Ok(m) = reader.read() {
            if let Message::Text(text) = m {
                let v: serde_json::Value = serde_json::from_str(&text).unwrap();
                if let Some(t) = v["t_s"].as_f64() {
                    *seen_by_reader.lock().unwrap() = t;
                }
            }
        }
    });
    wait_for(&view, &mut feed, |s| s.clients_dropped_slow == 1);
    // The reading client still gets new frames after the stuck one was dropped.
    let t_dropped = version.get() as f64;
    let s = wait_for(&view, &mut feed, |_| *seen.lock().unwrap() > t_dropped);
    assert_eq!((s.clients_connected, s.clients_dropped_slow), (2, 1));
    drop(stuck);
    drop(view);
    reading.join().unwrap();
}

#[test]
fn the_last_state_reaches_the_clients_when_the_view_stops() {
    let view = start(None);
    let mut ws = connect(view.local_addr());
    assert_eq!(next_text(&mut ws)["type"], "hello");
    view.publish(snapshot(1.0, None));
    assert_eq!(next_text(&mut ws)["t_s"], 1.0);
    let mut last = snapshot(2.0, None);
    last.mode = Some(FlightMode::Killed);
    view.publish(last);
    drop(view);
    let mut seen = Vec::new();
    while let Ok(m) = ws.read() {
        if let Message::Text(t) = m {
            let v: serde_json::Value = serde_json::from_str(&t).unwrap();
            seen.push(v["mode"].as_str().unwrap_or_default().to_string());
        }
    }
    assert_eq!(seen.last().map(String::as_str), Some("killed"), "{seen:?}");
}
