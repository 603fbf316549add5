//! The energy study's table: one line per setting with its hold error, energy, power parts and
//! its hold power's excess over the still hover, split into its causes.

use super::energy::Row;
use std::fmt::Write as _;

/// A gain as the table prints it: the value, or `default`.
fn gain(v: Option<f32>) -> String {
    v.map_or("default".into(), |v| v.to_string())
}

pub fn table(rows: &[Row], front: &[usize]) -> String {
    let mut t = String::from(
        "controller\tposition_kp\tvelocity_kp\tcommand_tau_s\tfailed\trms_hold_error_m\t\
         hold_energy_wh_per_min\tflight_motors_wh_per_min\tflight_escs_wh_per_min\t\
         flight_avionics_wh_per_min\thold_power_w\tmotor_jitter\tpareto\tstill_hover_w\t\
         excess_w\texcess_fraction",
    );
    if let Some(r) = rows.first() {
        for (name, _) in r.excess.parts() {
            let _ = write!(t, "\t{name}_w");
        }
    }
    t.push_str("\tpredicted_excess_w\n");
    for (i, r) in rows.iter().enumerate() {
        let g = &r.setting.gains;
        let [m, e, a] = r.parts_wh_min;
        let x = &r.excess;
        let _ = write!(
            t,
            "{}\t{}\t{}\t{}\t{}\t{:.5}\t{:.5}\t{m:.5}\t{e:.5}\t{a:.5}\t{:.3}\t{:.4}\t{}\t{:.3}\t{:.4}\t{:.6}",
            r.setting.controller.name(),
            gain(g.position_kp),
            gain(g.velocity_kp),
            gain(g.command_tau_s),
            r.failed,
            r.point.error_m,
            r.point.energy_wh_min,
            r.hold_power_w,
            r.jitter,
            front.contains(&i),
            x.floor_w,
            x.measured_w,
            x.measured_fraction(),
        );
        for (_, w) in x.parts() {
            let _ = write!(t, "\t{w:.4}");
        }
        let _ = writeln!(t, "\t{:.4}", x.predicted_w);
    }
    t
}
