//! The MAVLink inbound path: no panic on any bytes, split anywhere the same as whole, and every
//! event answerable (parameter replies, command acks) without a panic either; on a companion's
//! link, every autopilot estimate judged by an estimate watch without a panic, and nothing it
//! lets through non-finite.
#![no_main]
use libfuzzer_sys::fuzz_target;
use plumbline_core::flight::params::ParamError;
use plumbline_core::msgs::CommandResult;
use plumbline_link::{
    EstimateWatch, InboundEvent, Link, LinkConfig, LinkTime, ParameterStore, SigningKey,
    COMPONENT_ONBOARD_COMPUTER,
};

struct OneGain(f32);

impl ParameterStore for OneGain {
    fn count(&self) -> usize {
        1
    }
    fn name(&self, index: usize) -> Option<&str> {
        (index == 0).then_some("POS_XY_P")
    }
    fn value(&self, index: usize) -> Option<f32> {
        (index == 0).then_some(self.0)
    }
    fn set(&mut self, index: usize, value: f32) -> Result<f32, ParamError> {
        if index != 0 {
            return Err(ParamError::Unknown);
        }
        if !(0.0..=5.0).contains(&value) {
            return Err(ParamError::OutOfRange { min: 0.0, max: 5.0 });
        }
        self.0 = value;
        Ok(value)
    }
}

fn run(
    config: &LinkConfig,
    chunks: &[&[u8]],
) -> (Vec<InboundEvent>, Vec<u8>, plumbline_link::DropCounters) {
    let mut link = Link::new(config.clone());
    // The fixture's signing time, so the bundled signed frame is judged as fresh.
    let now = LinkTime::since(1_426_070_400.0, 0.0);
    let (mut events, mut replies) = (Vec::new(), Vec::new());
    for chunk in chunks {
        link.receive(chunk, now, &mut events, &mut replies);
    }
    let mut store = OneGain(1.0);
    let mut watch = EstimateWatch::new(0.5);
    for (i, event) in events.iter().enumerate() {
        match event {
            InboundEvent::Estimate(sample) => {
                // Each sample read a little later than the last, the watch asked every time.
                let t = i as f64 * 0.01;
                watch.take(sample, t);
                if let Ok(e) = watch.reading(t) {
                    assert!(e.valid && e.yaw_rad.is_finite());
                    assert!(e.position_m[..2].iter().all(|v| v.is_finite()));
                }
            }
            InboundEvent::Param { request, from } => {
                link.serve_param(request, *from, &mut store, now, &mut replies)
            }
            InboundEvent::Command { ack: Some(to), .. } => {
                link.acknowledge(*to, CommandResult::Accepted, now, &mut replies)
            }
            _ => {}
        }
    }
    (events, replies, *link.counters())
}

fuzz_target!(|data: &[u8]| {
    let keyed = LinkConfig {
        key: Some(SigningKey {
            secret: [7; 32],
            link_id: 0,
        }),
        ..LinkConfig::default()
    };
    let companion = LinkConfig {
        component_id: COMPONENT_ONBOARD_COMPUTER,
        ..LinkConfig::default()
    };
    for config in [LinkConfig::default(), keyed, companion] {
        let whole = run(&config, &[data]);
        let cut = data
            .first()
            .map_or(0, |&b| usize::from(b) % (data.len() + 1));
        let split = run(&config, &[&data[..cut], &data[cut..]]);
        // Compared as text: an estimate may carry NaN, which equals nothing.
        assert_eq!(format!("{:?}", whole.0), format!("{:?}", split.0));
        assert_eq!(whole.2, split.2);
        let counted = whole.2.skipped_bytes;
        assert!(counted <= data.len() as u64);
    }
});
