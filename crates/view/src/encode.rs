//! The websocket's messages: JSON text for the state, a PNG for the map (an occupancy grid of
//! a few hundred thousand cells compresses to a few kilobytes, and the browser decodes it).

use crate::snapshot::{OccupancyImage, Snapshot};
use plumbline_core::msgs::{FailsafeReason, FlightMode};
use serde::Serialize;

/// One state frame (`"type": "state"`).
#[derive(Serialize)]
struct StateMessage<'a> {
    r#type: &'static str,
    seq: u64,
    t_s: f64,
    /// x, y, z (m), yaw (rad).
    pose: [f64; 4],
    valid: bool,
    /// Scan hits as flat x, y pairs in centimetres: half the text of metres with decimals.
    scan_cm: Vec<i32>,
    battery_v: Option<f32>,
    mode: Option<&'a str>,
    failsafe: Option<&'a str>,
}

/// The map's geometry (`"type": "map"`); the PNG follows as the next, binary, message.
#[derive(Serialize)]
struct MapMessage {
    r#type: &'static str,
    version: u64,
    origin_m: [f64; 2],
    resolution_m: f64,
    width: usize,
    height: usize,
}

/// The first message a client gets (`"type": "hello"`).
#[derive(Serialize)]
struct HelloMessage<'a> {
    r#type: &'static str,
    controls: bool,
    /// The trail so far as flat x, y pairs, m.
    trail_m: &'a [f32],
}

/// A JSON number must be finite: a diverged estimate is sent as 0 with `valid` false.
fn finite(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

pub fn state(seq: u64, s: &Snapshot) -> String {
    let scan_cm = s
        .scan_m
        .iter()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .flat_map(|p| p.map(|v| (v * 100.0).round() as i32))
        .collect();
    let pose = s.pose.map(finite);
    let msg = StateMessage {
        r#type: "state",
        seq,
        t_s: finite(s.t_s),
        pose,
        valid: s.estimate_valid && s.pose.iter().all(|v| v.is_finite()),
        scan_cm,
        battery_v: s.battery_v.filter(|v| v.is_finite()),
        mode: s.mode.map(FlightMode::name),
        failsafe: s.failsafe.map(FailsafeReason::text),
    };
    serde_json::to_string(&msg).unwrap_or_default()
}

pub fn hello(controls: bool, trail_m: &[f32]) -> String {
    let msg = HelloMessage {
        r#type: "hello",
        controls,
        trail_m,
    };
    serde_json::to_string(&msg).unwrap_or_default()
}

/// The map's geometry message and its PNG; `None` for an image whose sizes do not agree.
pub fn map(m: &OccupancyImage) -> Option<(String, Vec<u8>)> {
    if !m.is_consistent() {
        return None;
    }
    let meta = MapMessage {
        r#type: "map",
        version: m.version,
        origin_m: m.origin_m,
        resolution_m: m.resolution_m,
        width: m.width,
        height: m.height,
    };
    let meta = serde_json::to_string(&meta).ok()?;
    Some((meta, png(m)?))
}

/// Grey 8-bit PNG, the top row the highest y so that the image is north-up as drawn.
fn png(m: &OccupancyImage) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, m.width as u32, m.height as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().ok()?;
    let flipped: Vec<u8> = m
        .cells
        .chunks_exact(m.width)
        .rev()
        .flatten()
        .copied()
        .collect();
    writer.write_image_data(&flipped).ok()?;
    writer.finish().ok()?;
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::snapshot::{FREE, OCCUPIED};

    #[test]
    fn a_map_round_trips_through_png_upside_down() {
        let m = OccupancyImage {
            version: 3,
            origin_m: [-1.0, 2.0],
            resolution_m: 0.5,
            width: 3,
            height: 2,
            cells: vec![OCCUPIED, FREE, FREE, FREE, FREE, OCCUPIED],
        };
        let (meta, bytes) = map(&m).unwrap();
        assert!(meta.contains("\"version\":3") && meta.contains("\"width\":3"));
        let mut reader = png::Decoder::new(bytes.as_slice()).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (3, 2));
        // Row 0 (lowest y) is the image's bottom row.
        assert_eq!(&buf[..6], &[FREE, FREE, OCCUPIED, OCCUPIED, FREE, FREE]);
    }

    #[test]
    fn inconsistent_maps_are_not_sent() {
        let mut m = OccupancyImage {
            version: 1,
            origin_m: [0.0, 0.0],
            resolution_m: 0.1,
            width: 4,
            height: 4,
            cells: vec![FREE; 15],
        };
        assert!(map(&m).is_none());
        m.cells.push(FREE);
        assert!(map(&m).is_some());
        m.resolution_m = f64::NAN;
        assert!(map(&m).is_none());
    }

    #[test]
    fn a_diverged_estimate_is_sent_as_invalid_numbers_json_accepts() {
        let s = Snapshot {
            pose: [f64::NAN, 1.0, f64::INFINITY, 0.0],
            estimate_valid: true,
            scan_m: vec![[0.011, -2.0], [f32::NAN, 1.0]],
            battery_v: Some(f32::NAN),
            mode: Some(FlightMode::Land),
            failsafe: Some(FailsafeReason::EstimateInvalid),
            ..Snapshot::default()
        };
        let text = state(7, &s);
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["valid"], false);
        assert_eq!(v["pose"][0], 0.0);
        assert_eq!(v["scan_cm"], serde_json::json!([1, -200]));
        assert!(v["battery_v"].is_null());
        assert_eq!(v["mode"], "land");
        assert_eq!(v["failsafe"], "estimate invalid");
    }
}
