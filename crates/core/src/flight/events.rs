//! A fixed-size log of mode changes, failsafes and controller fallbacks, so a flight can be explained afterwards
//! without a heap: the newest `N` events are kept and the number dropped is counted.

use crate::control::mrac::FallbackReason;
use crate::msgs::{FailsafeReason, FlightMode};

/// What happened.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EventKind {
    ModeChange {
        from: FlightMode,
        to: FlightMode,
    },
    Failsafe(FailsafeReason),
    /// The estimate lost one horizontal axis and a mission leg flies on with the other and
    /// the velocity ([`crate::estimate::validity`]); `false` when both axes are back.
    EstimateDegraded(bool),
    /// The MRAC's adaptive element was switched off (weights reset, baseline flying), or the
    /// MRAC could not be configured and the PID cascade flies.
    AdaptiveFallback(FallbackReason),
}

/// One logged event and when it happened (the step's `t_s`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    pub t_s: f64,
    pub kind: EventKind,
}

/// Ring buffer of the newest `N` events.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EventLog<const N: usize> {
    slots: [Option<Event>; N],
    /// Total events ever pushed; the next slot is `total % N`.
    total: u32,
}

impl<const N: usize> Default for EventLog<N> {
    fn default() -> Self {
        Self {
            slots: [None; N],
            total: 0,
        }
    }
}

impl<const N: usize> EventLog<N> {
    pub fn push(&mut self, t_s: f64, kind: EventKind) {
        if N == 0 {
            return;
        }
        self.slots[self.total as usize % N] = Some(Event { t_s, kind });
        self.total = self.total.wrapping_add(1);
    }

    /// Events ever pushed, kept or not.
    pub fn total(&self) -> u32 {
        self.total
    }

    /// Events pushed out by newer ones.
    pub fn dropped(&self) -> u32 {
        self.total.saturating_sub(N as u32)
    }

    /// The kept events, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = &Event> {
        let start = if (self.total as usize) < N {
            0
        } else {
            self.total as usize % N
        };
        (0..N).filter_map(move |k| self.slots[(start + k) % N].as_ref())
    }

    /// The most recent event.
    pub fn last(&self) -> Option<&Event> {
        if self.total == 0 || N == 0 {
            return None;
        }
        self.slots[(self.total as usize + N - 1) % N].as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mode(to: FlightMode) -> EventKind {
        EventKind::ModeChange {
            from: FlightMode::Disarmed,
            to,
        }
    }

    #[test]
    fn keeps_the_newest_in_order_and_counts_the_dropped() {
        let mut log = EventLog::<3>::default();
        assert!(log.last().is_none());
        log.push(1.0, mode(FlightMode::Takeoff));
        log.push(2.0, mode(FlightMode::Hold));
        assert_eq!(log.iter().map(|e| e.t_s).sum::<f64>(), 3.0);
        log.push(3.0, EventKind::Failsafe(FailsafeReason::BatteryLow));
        log.push(4.0, mode(FlightMode::Land));
        let times: [f64; 3] = {
            let mut it = log.iter().map(|e| e.t_s);
            [it.next().unwrap(), it.next().unwrap(), it.next().unwrap()]
        };
        assert_eq!(times, [2.0, 3.0, 4.0]);
        assert_eq!((log.total(), log.dropped()), (4, 1));
        assert_eq!(log.last().unwrap().kind, mode(FlightMode::Land));
    }
}
