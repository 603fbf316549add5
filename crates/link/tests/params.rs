//! The parameter protocol against a small store, as a ground station sees it.
mod common;

use common::*;
use plumbline_core::flight::params::ParamError;
use plumbline_link::common::{
    MavMessage, MavParamError, MavParamType, PARAM_REQUEST_LIST_DATA, PARAM_REQUEST_READ_DATA,
    PARAM_SET_DATA,
};
use plumbline_link::{InboundEvent, Link, LinkConfig, ParameterStore, SigningKey};

/// Two bounded gains, one with a name longer than MAVLink's 16 bytes.
struct Gains {
    names: [&'static str; 2],
    values: [f32; 2],
    bounds: [(f32, f32); 2],
}

impl Gains {
    fn new() -> Self {
        Self {
            names: ["POS_XY_P", "VELOCITY_LIMIT_HORIZONTAL"],
            values: [1.0, 2.0],
            bounds: [(0.0, 5.0), (0.1, 3.0)],
        }
    }
}

impl ParameterStore for Gains {
    fn count(&self) -> usize {
        2
    }
    fn name(&self, index: usize) -> Option<&str> {
        self.names.get(index).copied()
    }
    fn value(&self, index: usize) -> Option<f32> {
        self.values.get(index).copied()
    }
    fn set(&mut self, i: usize, value: f32) -> Result<f32, ParamError> {
        let (min, max) = *self.bounds.get(i).ok_or(ParamError::Unknown)?;
        if !value.is_finite() {
            return Err(ParamError::NotFinite);
        }
        if !(min..=max).contains(&value) {
            return Err(ParamError::OutOfRange { min, max });
        }
        self.values[i] = value;
        Ok(value)
    }
}

/// Feeds `message` and serves every parameter request it gives; returns the decoded replies.
fn exchange(
    link: &mut Link,
    store: &mut Gains,
    ground: &mut Ground,
    message: &MavMessage,
) -> Vec<MavMessage> {
    let (events, _) = feed(link, &ground.frame(message), at(0.0));
    let mut out = Vec::new();
    for event in events {
        let InboundEvent::Param { request, from } = event else {
            panic!("{event:?}")
        };
        link.serve_param(&request, from, store, at(0.0), &mut out);
    }
    decode_all(&out, None).into_iter().map(|(_, m)| m).collect()
}

fn set(name: &str, value: f32) -> MavMessage {
    MavMessage::PARAM_SET(PARAM_SET_DATA {
        param_value: value,
        target_system: 1,
        target_component: 1,
        param_id: name.into(),
        param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
    })
}

#[test]
fn list_read_and_set() {
    let (mut link, mut store, mut ground) = (
        Link::new(LinkConfig::default()),
        Gains::new(),
        Ground::unsigned(),
    );
    let list = MavMessage::PARAM_REQUEST_LIST(PARAM_REQUEST_LIST_DATA {
        target_system: 1,
        target_component: 1,
    });
    let replies = exchange(&mut link, &mut store, &mut ground, &list);
    let values: Vec<(String, f32, u16, u16)> = replies
        .iter()
        .map(|m| match m {
            MavMessage::PARAM_VALUE(v) => (
                v.param_id.to_str().unwrap().to_owned(),
                v.param_value,
                v.param_index,
                v.param_count,
            ),
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(
        values,
        [
            ("POS_XY_P".into(), 1.0, 0, 2),
            ("VELOCITY_LIMIT_H".into(), 2.0, 1, 2)
        ]
    );
    // Read by index and by (truncated) name.
    let read = |index: i16, name: &str| {
        MavMessage::PARAM_REQUEST_READ(PARAM_REQUEST_READ_DATA {
            param_index: index,
            target_system: 1,
            target_component: 1,
            param_id: name.into(),
        })
    };
    let by_index = exchange(&mut link, &mut store, &mut ground, &read(1, ""));
    let by_name = exchange(
        &mut link,
        &mut store,
        &mut ground,
        &read(-1, "VELOCITY_LIMIT_H"),
    );
    assert_eq!(by_index, by_name);
    // A set within bounds is applied and echoed, also through the truncated name.
    let replies = exchange(
        &mut link,
        &mut store,
        &mut ground,
        &set("VELOCITY_LIMIT_H", 2.5),
    );
    let [MavMessage::PARAM_VALUE(v)] = &replies[..] else {
        panic!("{replies:?}")
    };
    assert_eq!((v.param_value, v.param_index), (2.5, 1));
    assert_eq!(store.values[1], 2.5);
}

#[test]
fn out_of_range_and_unknown_parameters_are_refused_never_applied() {
    let (mut link, mut store, mut ground) = (
        Link::new(LinkConfig::default()),
        Gains::new(),
        Ground::unsigned(),
    );
    let replies = exchange(&mut link, &mut store, &mut ground, &set("POS_XY_P", 50.0));
    assert_eq!(store.values[0], 1.0);
    let [MavMessage::PARAM_ERROR(e), MavMessage::PARAM_VALUE(v), MavMessage::STATUSTEXT(t)] =
        &replies[..]
    else {
        panic!("{replies:?}")
    };
    assert_eq!(e.error, MavParamError::MAV_PARAM_ERROR_VALUE_OUT_OF_RANGE);
    assert_eq!(
        (e.target_system, e.param_id.to_str().unwrap()),
        (255, "POS_XY_P")
    );
    assert_eq!(v.param_value, 1.0, "the unchanged value");
    assert_eq!(
        t.text.to_str().unwrap(),
        "POS_XY_P 50: value outside [0, 5]"
    );
    let replies = exchange(&mut link, &mut store, &mut ground, &set("NO_SUCH", 1.0));
    let [MavMessage::PARAM_ERROR(e)] = &replies[..] else {
        panic!("{replies:?}")
    };
    assert_eq!(e.error, MavParamError::MAV_PARAM_ERROR_DOES_NOT_EXIST);
    let read_5 = MavMessage::PARAM_REQUEST_READ(PARAM_REQUEST_READ_DATA {
        param_index: 5,
        target_system: 1,
        target_component: 1,
        param_id: "".into(),
    });
    let replies = exchange(&mut link, &mut store, &mut ground, &read_5);
    let [MavMessage::PARAM_ERROR(e)] = &replies[..] else {
        panic!("{replies:?}")
    };
    assert_eq!(
        (e.param_index, e.error),
        (5, MavParamError::MAV_PARAM_ERROR_DOES_NOT_EXIST)
    );
    let nan = exchange(
        &mut link,
        &mut store,
        &mut ground,
        &set("POS_XY_P", f32::NAN),
    );
    assert!(matches!(nan[0], MavMessage::PARAM_ERROR(_)));
    assert_eq!(store.values, [1.0, 2.0]);
}

#[test]
fn a_param_set_flood_is_cut_to_the_configured_rate() {
    let mut link = Link::new(LinkConfig {
        param_set_per_s: 10.0,
        param_set_burst: 5.0,
        ..LinkConfig::default()
    });
    let mut ground = Ground::unsigned();
    let mut flood = Vec::new();
    for k in 0..100 {
        flood.extend(ground.frame(&set("POS_XY_P", k as f32 * 0.01)));
    }
    let (events, _) = feed(&mut link, &flood, at(0.0));
    assert_eq!(events.len(), 5);
    assert_eq!(link.counters().rate_limited, 95);
    // A second later ten more have been earned, capped at the burst.
    let (events, _) = feed(&mut link, &flood, at(1.0));
    assert_eq!(events.len(), 5);
}

#[test]
fn with_a_key_param_set_needs_a_signature_but_reading_does_not() {
    let mut link = Link::new(LinkConfig {
        key: Some(SigningKey {
            secret: KEY,
            link_id: 0,
        }),
        ..LinkConfig::default()
    });
    let (events, _) = feed(
        &mut link,
        &Ground::unsigned().frame(&set("POS_XY_P", 2.0)),
        at(0.0),
    );
    assert!(events.is_empty());
    assert_eq!(link.counters().unsigned, 1);
    let list = MavMessage::PARAM_REQUEST_LIST(PARAM_REQUEST_LIST_DATA {
        target_system: 1,
        target_component: 1,
    });
    let (events, _) = feed(&mut link, &Ground::unsigned().frame(&list), at(0.0));
    assert_eq!(events.len(), 1);
    let (events, _) = feed(
        &mut link,
        &Ground::signed(KEY).frame(&set("POS_XY_P", 2.0)),
        at(0.0),
    );
    assert_eq!(events.len(), 1);
}

#[test]
fn the_autopilots_parameter_names_fit_mavlink_and_are_unique() {
    use plumbline_core::flight::params;
    let names: Vec<&str> = (0..params::count())
        .map(|i| params::info(i).unwrap().name)
        .collect();
    assert!(names.len() > 10);
    for (i, name) in names.iter().enumerate() {
        assert!(
            name.len() <= plumbline_link::NAME_LEN && name.is_ascii(),
            "{name}"
        );
        assert!(!names[..i].contains(name), "{name} twice");
    }
}
