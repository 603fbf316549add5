//! The navigation EKF: state layout, covariance, and the one gated update every measurement
//! model goes through.
//!
//! State (world frame, f32): position (3), velocity (3), yaw, accelerometer bias (body, 3), gyro
//! z bias, the tilt error of the attitude filter (2) and of its gyro x/y bias (2), and a clone of
//! (x, y, yaw) at the scan matcher's reference scan. The clone makes the matcher's *relative* pose change an ordinary
//! measurement with correct correlations ("stochastic cloning"): the prediction is the current
//! pose seen from the cloned one. Roll and pitch come from [`super::attitude`]; the filter
//! carries that estimate's small error about world x and y, because a multirotor's accelerometer
//! sees mostly thrust and cannot tell tilt from acceleration, while the lidar can: a tilt error
//! turns into a velocity error the scan matches reveal, and the estimator feeds the estimated
//! error back into the tilt filter. The biases kept are the ones that drift the hold point
//! (horizontal accelerometer bias, and the gyro x/y bias, which turns the tilt at a steady rate:
//! the tilt filter's own slow integral left up to 0.003 rad/s there, 0.2 degrees of tilt a second
//! once the lidar stops correcting it), the height (vertical accelerometer bias) and the heading
//! (gyro z bias).

use nalgebra::{SMatrix, SVector};

/// Number of states.
pub const N: usize = 18;
/// Indices into the state vector.
pub mod ix {
    pub const POS: usize = 0;
    pub const VEL: usize = 3;
    pub const YAW: usize = 6;
    pub const ACCEL_BIAS: usize = 7;
    pub const GYRO_Z_BIAS: usize = 10;
    /// Small-angle error of the tilt filter about world x and y (true = exp(error) * estimate).
    pub const TILT: usize = 11;
    /// Error of the tilt filter's gyro bias about body x and y (true = estimate + error).
    pub const GYRO_XY_BIAS: usize = 13;
    /// Clone of x, y and yaw at the reference scan.
    pub const CLONE: usize = 15;
}

pub type State = SVector<f32, N>;
pub type Covariance = SMatrix<f32, N, N>;

/// Noise, gating and validity settings of the EKF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EkfConfig {
    /// Initial one-sigma of position (m), velocity (m/s), yaw (rad). The yaw's is 0 because
    /// the estimate frame's heading is the heading at power-up: a choice, not a quantity to
    /// estimate, and nothing onboard measures it afterwards (the scan matches measure the
    /// heading against references that inherit it, super::frame). A variance there is a
    /// freedom of the whole frame that the filter spends: with 0.05 rad the correlations the
    /// gyro noise builds with the measured relative heading let the first accelerations of a
    /// flight turn the frame by 0.02 rad, the flown path turned with it about the start (the
    /// 3 m square with the UTM-30LX: estimate error 0.035 m, 0.010 m with 0).
    pub initial_std: [f32; 3],
    /// Initial one-sigma of accelerometer bias (m/s^2) and gyro bias (rad/s; z, and the error of
    /// the tilt filter's x/y estimate).
    pub initial_bias_std: [f32; 2],
    /// Initial one-sigma of the tilt filter's error (rad).
    pub initial_tilt_std_rad: f32,
    /// Accelerometer white noise density (m/s^2/sqrt(Hz)), including what tilt-estimate error
    /// adds to the horizontal specific force.
    pub accel_noise_density: f32,
    /// Gyro z white noise density (rad/s/sqrt(Hz)).
    pub gyro_noise_density: f32,
    /// Bias random walks: accelerometer (m/s^3/sqrt(Hz)) and gyro (rad/s^2/sqrt(Hz)).
    pub accel_bias_walk: f32,
    pub gyro_bias_walk: f32,
    /// The covariance is propagated at most this often (s); the state every step. Keeps the
    /// N x N products off the per-IMU-sample path. 20 ms: at 10 ms it is a sixth of the
    /// onboard stack's cost, and the simulated holds do not tell the two apart (xv11 60 s seeds
    /// 1-80, RMS 1.63 against 1.62 cm, no estimate slip at either).
    pub covariance_period_s: f32,
    /// Normalised innovation squared above which a measurement is rejected, for 1, 2 and 3
    /// dimensions (chi-square 99.7 %).
    pub gate_nis: [f32; 3],
    /// The horizontal position is known along a principal axis of its covariance while the
    /// one-sigma along it is within this (m); the estimate is valid while both are
    /// ([`super::validity`]).
    pub max_position_std_m: f32,
    /// Bounds of the degraded estimate, known across one axis only, on which a mission leg
    /// flies on ([`super::validity`]): the one-sigma of the velocity (m/s) and of the position
    /// (m) along the unknown axis. The velocity's: 0.5 m/s is the guidance's top speed, and a
    /// vehicle whose speed along the corridor is that uncertain no longer knows whether it is
    /// stopping. The position's keeps the map pose and the way home within what the companion
    /// can match again (a short-range lidar's reach), and it bounds how long a leg flies on a
    /// speed nothing but the drag reading checks. With the drag reading the position's is the
    /// one that ends a blank span: in the simulated building the speed one-sigma settles near
    /// 0.47 m/s while the position's grows about 0.2 m/s past 3 m. Flown on past it, with the
    /// velocity bound alone, most degraded legs still ended a few seconds later, as the speed's
    /// one-sigma reached 0.5 m/s; with the velocity bound widened as well, one leg's speed error
    /// grew to 1.3 m/s, nearly three of its one-sigmas, and it flew into a corridor's end wall.
    pub degraded_max_velocity_std_m_s: f32,
    pub degraded_max_position_std_m: f32,
    /// After this many consecutive rejections of one sensor, the filter stops trusting its own
    /// prediction of what that sensor sees: the measured states' variance is reset so the next
    /// measurement is taken. Without this, a filter that has drifted (an unsensed touchdown
    /// shock, a long lidar outage) would reject every correction forever.
    pub reset_after_rejections: u32,
    /// Scan matches reopen the filter on time as well as on count: once they have been
    /// refused for this long (s, from the run's first refusal), the horizontal states are
    /// reopened and the refused match is used at once. The run must end within the
    /// supervisor's lidar timeout (1 s from the last accepted match): a filter refusing good
    /// matches for longer raises "lidar lost", holds on the IMU and lands before the matcher
    /// can pull it back, and ten refusals of the XV-11's 4 Hz revolutions take 2.5 s. 0.5 s is
    /// the third refusal at 4 Hz (0.75 s after the last acceptance), the sixth at 10 Hz.
    pub scan_reopen_after_s: f32,
    /// One-sigma given to reopened states: horizontal position (m; below
    /// `max_position_std_m`, so a reopened estimate stays flyable), height (m), velocity (m/s)
    /// and yaw (rad). Wide enough that the next measurement passes the gate.
    pub reopen_std: [f32; 4],
    /// Factor on the scan matcher's covariance: point-to-line covariances assume independent,
    /// unbiased range errors and come out optimistic for a noisy lidar.
    pub scan_covariance_scale: f32,
}

impl Default for EkfConfig {
    fn default() -> Self {
        Self {
            initial_std: [0.05, 0.05, 0.0],
            initial_bias_std: [0.3, 0.01],
            initial_tilt_std_rad: 0.02,
            accel_noise_density: 0.15,
            gyro_noise_density: 0.005,
            accel_bias_walk: 0.01,
            gyro_bias_walk: 0.0005,
            covariance_period_s: 0.02,
            // Three times the chi-square 99.7 % points (8.81, 11.62, 14.16): during an
            // aggressive recovery (a push, 15 degrees of tilt) the prediction is more wrong than
            // its covariance says, and the 99.7 % gate threw away the scan matches needed to
            // recover (1 in 20 seeds hit a wall; twice the points still lost 2 in 100). Gross
            // outliers (a match 0.5 m off at 5 cm) still score around 100.
            gate_nis: [26.4, 34.9, 42.5],
            max_position_std_m: 1.5,
            degraded_max_velocity_std_m_s: 0.5,
            degraded_max_position_std_m: 3.0,
            reset_after_rejections: 10,
            scan_reopen_after_s: 0.5,
            reopen_std: [1.0, 5.0, 1.0, 0.3],
            // Tuned in the simulator with the XV-11 profile (crates/sim/tests/closed_loop.rs).
            scan_covariance_scale: 10.0,
        }
    }
}

/// What became of one measurement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    Accepted,
    /// Failed the innovation gate; the state is unchanged.
    Rejected,
    /// Non-finite or ill-formed (bad covariance, singular innovation); the state is unchanged.
    Invalid,
}

/// Per-measurement-model tallies, kept so faults are counted rather than silently dropped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub accepted: u32,
    pub rejected: u32,
    pub invalid: u32,
    /// Rejections since the last acceptance.
    pub consecutive_rejected: u32,
    /// Times the rejections ran so long that the filter reset the measured states' variance.
    pub resets: u32,
}

impl Counters {
    pub fn record(&mut self, outcome: Outcome) {
        match outcome {
            Outcome::Accepted => {
                self.accepted = self.accepted.saturating_add(1);
                self.consecutive_rejected = 0;
            }
            Outcome::Rejected => {
                self.rejected = self.rejected.saturating_add(1);
                self.consecutive_rejected = self.consecutive_rejected.saturating_add(1);
            }
            Outcome::Invalid => self.invalid = self.invalid.saturating_add(1),
        }
    }

    /// Records an outcome; true when it completes a run of `limit` rejections, which the caller
    /// answers by reopening the measured states (the run is then counted as a reset).
    pub fn record_gated(&mut self, outcome: Outcome, limit: u32) -> bool {
        self.record(outcome);
        if self.consecutive_rejected < limit.max(1) {
            return false;
        }
        self.record_gated_now()
    }

    /// Ends the current run of rejections as a reset (the caller reopens the measured states);
    /// true when there was a run to end.
    pub fn record_gated_now(&mut self) -> bool {
        if self.consecutive_rejected == 0 {
            return false;
        }
        self.consecutive_rejected = 0;
        self.resets = self.resets.saturating_add(1);
        true
    }
}

/// The filter: state, covariance and the covariance-propagation accumulator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ekf {
    pub config: EkfConfig,
    pub(super) x: State,
    pub(super) p: Covariance,
    /// The motion since the covariance last caught up with the state.
    pub(super) pending: super::imu::PendingMotion,
    /// True once a reference pose has been cloned.
    pub(super) has_reference: bool,
}

impl Ekf {
    pub fn new(config: EkfConfig) -> Self {
        let mut p = Covariance::zeros();
        let [sp, sv, sy] = config.initial_std;
        let [sa, sg] = config.initial_bias_std;
        for i in 0..3 {
            p[(ix::POS + i, ix::POS + i)] = sp * sp;
            p[(ix::VEL + i, ix::VEL + i)] = sv * sv;
            p[(ix::ACCEL_BIAS + i, ix::ACCEL_BIAS + i)] = sa * sa;
        }
        p[(ix::YAW, ix::YAW)] = sy * sy;
        p[(ix::GYRO_Z_BIAS, ix::GYRO_Z_BIAS)] = sg * sg;
        for i in 0..2 {
            p[(ix::TILT + i, ix::TILT + i)] =
                config.initial_tilt_std_rad * config.initial_tilt_std_rad;
            p[(ix::GYRO_XY_BIAS + i, ix::GYRO_XY_BIAS + i)] = sg * sg;
        }
        for i in 0..3 {
            p[(ix::CLONE + i, ix::CLONE + i)] = 1.0;
        }
        Self {
            config,
            x: State::zeros(),
            p,
            pending: Default::default(),
            has_reference: false,
        }
    }

    /// The state vector (see [`ix`]).
    pub fn state(&self) -> &State {
        &self.x
    }

    /// The covariance matrix.
    pub fn covariance(&self) -> &Covariance {
        &self.p
    }

    /// Finite state and covariance, and the horizontal position known along both principal
    /// axes ([`super::validity`]).
    pub fn is_valid(&self) -> bool {
        self.horizontal() == super::validity::Horizontal::Known
    }

    /// No NaN or infinity in the state or the covariance, and no negative variance.
    pub(super) fn is_finite(&self) -> bool {
        // The diagonal suffices: a non-finite covariance entry reaches the diagonal at the next
        // propagation, and checking every entry each step cost more than the prediction. This
        // runs every step, so two instructions a value and no branch: a NaN or an infinity
        // anywhere makes the sum NaN or infinite (so would a sum past f32's range, 1e38, which
        // no flyable filter holds).
        let diagonal = self.p.as_slice().iter().step_by(N + 1);
        let (mut sum, mut lowest) = (0.0f32, 0.0f32);
        for (x, &v) in self.x.as_slice().iter().zip(diagonal) {
            sum += x + v;
            lowest = if v < lowest { v } else { lowest };
        }
        sum * 0.0 == 0.0 && lowest >= 0.0
    }

    /// Hands out the estimated tilt-filter errors and zeroes them: the tilt (about world x, y;
    /// rad) and the gyro x/y bias (body; rad/s). The caller applies them to the tilt filter (the
    /// error-state reset; covariance is kept).
    pub fn take_tilt_error(&mut self) -> ([f32; 2], [f32; 2]) {
        let take =
            |x: &mut State, i: usize| [core::mem::take(&mut x[i]), core::mem::take(&mut x[i + 1])];
        let tilt = take(&mut self.x, ix::TILT);
        let bias = take(&mut self.x, ix::GYRO_XY_BIAS);
        (tilt, bias)
    }

    /// Forgets what the filter knew about the given states: their correlations are cut and
    /// their variances set, so the next measurement of them is believed.
    pub fn reset_variance(&mut self, states: &[(usize, f32)]) {
        for &(i, variance) in states {
            self.p.row_mut(i).fill(0.0);
            self.p.column_mut(i).fill(0.0);
            self.p[(i, i)] = variance;
        }
    }

    /// Makes (x, y, yaw) as they were `latency_s` ago (position taken back along the velocity)
    /// the reference pose of the scan matcher: the clone takes the values and all the
    /// correlations of those combinations of live states.
    pub fn clone_reference(&mut self, latency_s: f32) {
        let l = latency_s;
        // Clone k = live k - l * (velocity k), for x and y; yaw as it is.
        let live = [
            (ix::POS, Some(ix::VEL)),
            (ix::POS + 1, Some(ix::VEL + 1)),
            (ix::YAW, None),
        ];
        let combine = |x: &State, p: &Covariance, k: usize, row: bool| {
            let (src, vel) = live[k];
            let mut v = if row {
                p.row(src).transpose().into_owned()
            } else {
                p.column(src).into_owned()
            };
            if let Some(vi) = vel {
                let d = if row {
                    p.row(vi).transpose().into_owned()
                } else {
                    p.column(vi).into_owned()
                };
                v -= d * l;
            }
            let value = x[src] - vel.map_or(0.0, |vi| l * x[vi]);
            (value, v)
        };
        for k in 0..3 {
            let (value, row) = combine(&self.x, &self.p, k, true);
            self.x[ix::CLONE + k] = value;
            self.p.set_row(ix::CLONE + k, &row.transpose());
        }
        for k in 0..3 {
            let (_, col) = combine(&self.x, &self.p, k, false);
            self.p.set_column(ix::CLONE + k, &col);
        }
        // The clones' own block came out of the column passes, each entry and its mirror by
        // different roundings: one triangle is copied onto the other, so P stays exactly
        // symmetric.
        for a in 1..3 {
            for b in 0..a {
                self.p[(ix::CLONE + b, ix::CLONE + a)] = self.p[(ix::CLONE + a, ix::CLONE + b)];
            }
        }
        self.has_reference = true;
    }

    /// The gated Kalman update shared by every measurement model: `residual = z - h(x)`,
    /// Jacobian `h`, noise `r`. Joseph-form covariance update, so rounding in f32 keeps it
    /// symmetric positive semi-definite.
    pub fn update<const M: usize>(
        &mut self,
        residual: SVector<f32, M>,
        h: SMatrix<f32, M, N>,
        r: SMatrix<f32, M, M>,
    ) -> Outcome {
        let gate = self.config.gate_nis[(M - 1).min(2)];
        self.update_considering(residual, h, r, &[], gate)
    }

    /// [`Self::update`] that leaves the states in `consider` alone (their gain rows are zero;
    /// the Schmidt-Kalman "consider" update), with its own innovation gate. The Joseph form
    /// keeps the covariance right for any gain, so their variances and correlations still
    /// account for the measurement.
    pub fn update_considering<const M: usize>(
        &mut self,
        residual: SVector<f32, M>,
        h: SMatrix<f32, M, N>,
        r: SMatrix<f32, M, M>,
        consider: &[usize],
        gate_nis: f32,
    ) -> Outcome {
        if !(all_finite(residual.as_slice())
            && all_finite(h.as_slice())
            && all_finite(r.as_slice()))
        {
            return Outcome::Invalid;
        }
        if !well_conditioned(&r) {
            return Outcome::Invalid;
        }
        let pht = times_ht(&self.p, &h);
        let s = h * pht + r;
        let Some(chol) = s.cholesky() else {
            return Outcome::Invalid;
        };
        let nis = residual.dot(&chol.solve(&residual));
        if !nis.is_finite() {
            return Outcome::Invalid;
        }
        if nis > gate_nis {
            return Outcome::Rejected;
        }
        let mut k = pht * chol.inverse();
        for &i in consider {
            k.row_mut(i).fill(0.0);
        }
        let before = self.x;
        self.x += k * residual;
        self.joseph(&k, &h, &r, &pht);
        self.follow_frame_turn(&before);
        self.x[ix::YAW] = crate::geom::normalize_angle(self.x[ix::YAW]);
        Outcome::Accepted
    }
}

impl Ekf {
    /// `P = (I - KH) P (I - KH)^T + K R K^T` (Joseph form) as products, for any gain (zeroed
    /// consider rows included), then symmetrised. A sum of two positive semi-definite terms,
    /// so rounding cannot take it far below zero whatever the gain's own rounding; the same
    /// form multiplied out (`P - K U^T - U K^T + K S K^T`) cancels terms of the size of S and
    /// with a noise of 1e4 along one direction and 1e-5 across it left variances negative.
    /// `pht` is `P H^T`, so `(I - KH) P = P - K pht^T`; with H sparse and M small every
    /// product is O(N^2 M).
    fn joseph<const M: usize>(
        &mut self,
        k: &SMatrix<f32, N, M>,
        h: &SMatrix<f32, M, N>,
        r: &SMatrix<f32, M, M>,
        pht: &SMatrix<f32, N, M>,
    ) {
        // Worked in place: every N x N temporary is 1.3 KB of a microcontroller's stack.
        let p = &mut self.p;
        p.gemm(-1.0, k, &pht.transpose(), 1.0);
        let a_p_ht = times_ht(p, h);
        // (I - KH) P (I - KH)^T + K R K^T = A P - (A P H^T - K R) K^T.
        p.gemm(-1.0, &(a_p_ht - k * r), &k.transpose(), 1.0);
        symmetrise(p);
    }
}

/// Smallest pivot of the noise's Cholesky factor against its own variance that f32 holds
/// faithfully. Each pivot is a variance minus what the earlier rows explain of it, so rounding
/// errs by about 6e-8 of that variance: a noise of 1e4 along a rotated axis and 1e-5 across
/// it is, once stored, whatever the rounding made of the small variance, often negative.
/// 1e-5 leaves the rounding a hundredth of the pivot.
const MIN_NOISE_PIVOT: f32 = 1e-5;

/// Noise that is positive definite by a margin f32 can hold. Noise that is not claims more than
/// perfect knowledge in some direction: the update would take out more variance than the state
/// has, and the covariance would stop being positive semi-definite whatever form the update
/// takes.
fn well_conditioned<const M: usize>(r: &SMatrix<f32, M, M>) -> bool {
    let Some(chol) = r.cholesky() else {
        return false;
    };
    let l = chol.l_dirty();
    (0..M).all(|i| l[(i, i)] * l[(i, i)] >= MIN_NOISE_PIVOT * r[(i, i)])
}

/// Replaces `p` by `(p + pᵀ) / 2` in place (the same values as the expression, without its
/// two N x N temporaries).
pub(super) fn symmetrise(p: &mut Covariance) {
    for i in 0..N {
        for j in i + 1..N {
            let mean = (p[(i, j)] + p[(j, i)]) * 0.5;
            p[(i, j)] = mean;
            p[(j, i)] = mean;
        }
    }
}

/// True when no value is NaN or infinite (v * 0 is 0 for finite v and NaN otherwise): cheaper
/// than `is_finite` per value, which is several integer operations.
pub(crate) fn all_finite(values: &[f32]) -> bool {
    values.iter().fold(0.0f32, |sum, v| sum + v * 0.0) == 0.0
}

/// `m h^T`, visiting only the non-zero entries of `h`: a measurement sees a few of the N
/// states, and dense products would be most of an update's cost.
fn times_ht<const M: usize>(m: &Covariance, h: &SMatrix<f32, M, N>) -> SMatrix<f32, N, M> {
    let mut out = SMatrix::<f32, N, M>::zeros();
    for state in 0..N {
        for row in 0..M {
            let v = h[(row, state)];
            if v != 0.0 {
                out.column_mut(row).axpy(v, &m.column(state), 1.0);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn update_pulls_toward_the_measurement_by_the_variance_ratio() {
        let mut f = Ekf::new(EkfConfig::default());
        // Position x has variance 0.05^2; measure x = 0.1 with the same variance: halfway.
        let mut h = SMatrix::<f32, 1, N>::zeros();
        h[(0, ix::POS)] = 1.0;
        let r = SMatrix::<f32, 1, 1>::new(0.0025);
        let out = f.update(SVector::<f32, 1>::new(0.1), h, r);
        assert_eq!(out, Outcome::Accepted);
        assert!((f.state()[ix::POS] - 0.05).abs() < 1e-5);
        assert!((f.covariance()[(ix::POS, ix::POS)] - 0.00125).abs() < 1e-6);
    }

    #[test]
    fn update_equals_the_joseph_form_for_a_consider_gain() {
        let mut f = Ekf::new(EkfConfig::default());
        // A full, symmetric covariance so every entry of the product matters.
        for i in 0..N {
            for j in 0..N {
                let v = 0.002 * (i + 2 * j) as f32 / N as f32;
                f.p[(i, j)] = if i == j { 0.05 } else { v };
            }
        }
        f.p = (f.p + f.p.transpose()) * 0.5;
        let mut h = SMatrix::<f32, 2, N>::zeros();
        h[(0, ix::POS)] = 1.0;
        h[(0, ix::VEL)] = -0.1;
        h[(1, ix::YAW)] = 0.8;
        h[(1, ix::ACCEL_BIAS + 1)] = 1.0;
        let r = SMatrix::<f32, 2, 2>::new(0.01, 0.002, 0.002, 0.02);
        // The horizontal positions and velocities considered too: no correction moves them, so
        // the covariance is not re-expressed about a turned frame (super::frame) and is the
        // Joseph form's alone.
        let consider = [
            ix::POS,
            ix::POS + 1,
            ix::VEL,
            ix::VEL + 1,
            ix::CLONE,
            ix::CLONE + 1,
        ];
        let before = f.p;
        let s = h * before * h.transpose() + r;
        let mut k = before * h.transpose() * s.try_inverse().unwrap();
        for &i in &consider {
            k.row_mut(i).fill(0.0);
        }
        let a = Covariance::identity() - k * h;
        let joseph = a * before * a.transpose() + k * r * k.transpose();
        let residual = SVector::<f32, 2>::new(0.01, -0.02);
        let out = f.update_considering(residual, h, r, &consider, 100.0);
        assert_eq!(out, Outcome::Accepted);
        assert!((f.p - joseph).abs().max() < 1e-6);
        assert_eq!(f.p, f.p.transpose());
    }

    #[test]
    fn gate_rejects_an_outlier_and_leaves_the_state_alone() {
        let mut f = Ekf::new(EkfConfig::default());
        let before = f;
        let mut h = SMatrix::<f32, 1, N>::zeros();
        h[(0, ix::POS)] = 1.0;
        // 1 m off with 0.07 m innovation sigma: NIS ~ 200, far past the gate.
        let out = f.update(
            SVector::<f32, 1>::new(1.0),
            h,
            SMatrix::<f32, 1, 1>::new(0.0025),
        );
        assert_eq!(out, Outcome::Rejected);
        assert_eq!(f, before);
        let mut c = Counters::default();
        c.record(out);
        c.record(out);
        assert_eq!((c.rejected, c.consecutive_rejected), (2, 2));
        c.record(Outcome::Accepted);
        assert_eq!((c.rejected, c.consecutive_rejected, c.accepted), (2, 0, 1));
    }

    #[test]
    fn ill_formed_measurements_are_invalid() {
        let mut f = Ekf::new(EkfConfig::default());
        let mut h = SMatrix::<f32, 1, N>::zeros();
        h[(0, ix::POS)] = 1.0;
        let nan = f.update(
            SVector::<f32, 1>::new(f32::NAN),
            h,
            SMatrix::<f32, 1, 1>::new(0.01),
        );
        assert_eq!(nan, Outcome::Invalid);
        // Negative noise makes the innovation covariance indefinite.
        let bad = f.update(
            SVector::<f32, 1>::new(0.0),
            h,
            SMatrix::<f32, 1, 1>::new(-1.0),
        );
        assert_eq!(bad, Outcome::Invalid);
        // 1e4 along a diagonal and 1e-5 across it: in f32 the small variance is lost in the
        // rounding of the large one (a corridor's unobserved axis, rotated).
        let mut h2 = SMatrix::<f32, 2, N>::zeros();
        h2[(0, ix::POS)] = 1.0;
        h2[(1, ix::POS + 1)] = 1.0;
        let (along, across) = (1e4f32, 1e-5f32);
        let r = SMatrix::<f32, 2, 2>::new(
            0.5 * (along + across),
            0.5 * (along - across),
            0.5 * (along - across),
            0.5 * (along + across),
        );
        assert_eq!(f.update(SVector::zeros(), h2, r), Outcome::Invalid);
        // The same noise along the axes is held exactly, and fused.
        let r = SMatrix::<f32, 2, 2>::new(along, 0.0, 0.0, across);
        assert_eq!(f.update(SVector::zeros(), h2, r), Outcome::Accepted);
        assert!(f.is_valid());
    }

    #[test]
    fn considered_states_keep_their_value_and_variance() {
        let mut f = Ekf::new(EkfConfig::default());
        // Position and velocity correlated, as after a stretch of prediction.
        f.p[(ix::POS, ix::VEL)] = 1e-3;
        f.p[(ix::VEL, ix::POS)] = 1e-3;
        let (p_before, var_before) = (f.x[ix::POS], f.p[(ix::POS, ix::POS)]);
        let mut h = SMatrix::<f32, 1, N>::zeros();
        h[(0, ix::VEL)] = 1.0;
        let r = SMatrix::<f32, 1, 1>::new(0.0025);
        let out = f.update_considering(SVector::<f32, 1>::new(0.1), h, r, &[ix::POS], 8.81);
        assert_eq!(out, Outcome::Accepted);
        assert!(f.x[ix::VEL] > 0.04, "{}", f.x[ix::VEL]);
        assert_eq!(
            (f.x[ix::POS], f.p[(ix::POS, ix::POS)]),
            (p_before, var_before)
        );
        // The correlation shrinks with the velocity's variance.
        assert!(f.p[(ix::POS, ix::VEL)] < 1e-3);
        assert_eq!(f.p, f.p.transpose());
        // A plain update moves the correlated position too.
        let mut g = Ekf::new(EkfConfig::default());
        g.p[(ix::POS, ix::VEL)] = 1e-3;
        g.p[(ix::VEL, ix::POS)] = 1e-3;
        g.update(SVector::<f32, 1>::new(0.1), h, r);
        assert!(g.x[ix::POS] > 0.01, "{}", g.x[ix::POS]);
    }

    #[test]
    fn the_sparse_product_equals_the_dense_one() {
        let mut p = Covariance::zeros();
        for i in 0..N {
            for j in 0..N {
                p[(i, j)] = 0.1 + (i * N + j) as f32 * 0.01;
            }
        }
        let mut h = SMatrix::<f32, 2, N>::zeros();
        h[(0, ix::VEL)] = -0.7;
        h[(0, ix::YAW)] = 0.2;
        h[(1, ix::ACCEL_BIAS + 1)] = 1.0;
        assert!((times_ht(&p, &h) - p * h.transpose()).abs().max() < 1e-6);
    }

    #[test]
    fn validity_catches_every_non_finite_state_and_a_bad_variance() {
        let f = Ekf::new(EkfConfig::default());
        assert!(f.is_valid());
        for i in 0..N {
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                let mut g = f;
                g.x[i] = bad;
                assert!(!g.is_valid(), "state {i} = {bad}");
                let mut g = f;
                g.p[(i, i)] = bad;
                assert!(!g.is_valid(), "variance {i} = {bad}");
            }
            let mut g = f;
            g.p[(i, i)] = -1e-3;
            assert!(!g.is_valid(), "variance {i} negative");
        }
        let mut wide = f;
        wide.p[(ix::POS + 1, ix::POS + 1)] = 2.0 * 2.0;
        assert!(!wide.is_valid());
    }

    #[test]
    fn reset_variance_cuts_correlations() {
        let mut f = Ekf::new(EkfConfig::default());
        f.p[(ix::POS + 2, ix::VEL + 2)] = 1e-3;
        f.p[(ix::VEL + 2, ix::POS + 2)] = 1e-3;
        f.reset_variance(&[(ix::POS + 2, 4.0)]);
        assert_eq!(f.p[(ix::POS + 2, ix::POS + 2)], 4.0);
        assert_eq!(f.p[(ix::POS + 2, ix::VEL + 2)], 0.0);
        assert_eq!(f.p, f.p.transpose());
    }

    #[test]
    fn clone_copies_values_and_correlations() {
        let mut f = Ekf::new(EkfConfig::default());
        f.x[ix::POS] = 1.5;
        f.x[ix::YAW] = 0.3;
        f.p[(ix::POS, ix::VEL)] = 1e-3;
        f.p[(ix::VEL, ix::POS)] = 1e-3;
        f.clone_reference(0.0);
        assert_eq!(f.x[ix::CLONE], 1.5);
        assert_eq!(f.x[ix::CLONE + 2], 0.3);
        assert_eq!(f.p[(ix::CLONE, ix::VEL)], 1e-3);
        assert_eq!(f.p[(ix::CLONE, ix::CLONE)], f.p[(ix::POS, ix::POS)]);
        assert_eq!(f.p[(ix::CLONE, ix::POS)], f.p[(ix::POS, ix::POS)]);
        assert_eq!(f.p, f.p.transpose());
        // Taken back along the velocity from a full covariance, it stays exactly symmetric.
        for i in 0..N {
            for j in 0..=i {
                let v = if i == j {
                    0.04
                } else {
                    1e-3 / (1 + i + j) as f32
                };
                f.p[(i, j)] = v;
                f.p[(j, i)] = v;
            }
        }
        f.clone_reference(0.1);
        assert_eq!(f.p, f.p.transpose());
    }
}
