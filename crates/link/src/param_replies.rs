//! The replies of the parameter protocol, from the caller's [`ParameterStore`].

use crate::link::{Link, LinkTime, Peer};
use crate::params::{truncate, ParamName, ParamRef, ParamRequest, ParameterStore};
use mavlink::dialects::common::{
    MavMessage, MavParamError, MavParamType, MavSeverity, PARAM_ERROR_DATA, PARAM_VALUE_DATA,
};
use plumbline_core::flight::params::ParamError;

pub(crate) fn serve(
    link: &mut Link,
    request: &ParamRequest,
    from: Peer,
    store: &mut dyn ParameterStore,
    now: LinkTime,
    out: &mut Vec<u8>,
) {
    match *request {
        ParamRequest::List => {
            for index in 0..store.count() {
                send_value(link, store, index, now, out);
            }
        }
        ParamRequest::Read(ParamRef::Index(i)) if usize::from(i) < store.count() => {
            send_value(link, store, usize::from(i), now, out);
        }
        ParamRequest::Read(ParamRef::Index(i)) => {
            send_error(
                link,
                from,
                None,
                Some(i),
                MavParamError::MAV_PARAM_ERROR_DOES_NOT_EXIST,
                now,
                out,
            );
        }
        ParamRequest::Read(ParamRef::Name(name)) => match lookup(store, &name) {
            Some(index) => send_value(link, store, index, now, out),
            None => send_error(
                link,
                from,
                Some(&name),
                None,
                MavParamError::MAV_PARAM_ERROR_DOES_NOT_EXIST,
                now,
                out,
            ),
        },
        ParamRequest::Set { name, value } => {
            let Some(index) = lookup(store, &name) else {
                return send_error(
                    link,
                    from,
                    Some(&name),
                    None,
                    MavParamError::MAV_PARAM_ERROR_DOES_NOT_EXIST,
                    now,
                    out,
                );
            };
            match store.set(index, value) {
                Ok(_) => send_value(link, store, index, now, out),
                Err(refusal) => {
                    send_error(
                        link,
                        from,
                        Some(&name),
                        None,
                        param_error(&refusal),
                        now,
                        out,
                    );
                    send_value(link, store, index, now, out);
                    let text = format!("{} {value}: {refusal}", name.as_str().unwrap_or_default());
                    link.statustext(MavSeverity::MAV_SEVERITY_WARNING, &text, now, out);
                }
            }
        }
    }
}

/// MAV_PARAM_ERROR of a refusal: a value the parameter cannot take (outside its bounds, not a
/// number, against another parameter's) is out of range; a parameter that cannot change while
/// armed is a permission matter.
fn param_error(refusal: &ParamError) -> MavParamError {
    match refusal {
        ParamError::Unknown => MavParamError::MAV_PARAM_ERROR_DOES_NOT_EXIST,
        ParamError::NotFinite | ParamError::OutOfRange { .. } | ParamError::Inconsistent { .. } => {
            MavParamError::MAV_PARAM_ERROR_VALUE_OUT_OF_RANGE
        }
        ParamError::NotWhileArmed => MavParamError::MAV_PARAM_ERROR_PERMISSION_DENIED,
    }
}

fn lookup(store: &dyn ParameterStore, name: &ParamName) -> Option<usize> {
    name.as_str().and_then(|n| store.index_of(n))
}

fn send_value(
    link: &mut Link,
    store: &dyn ParameterStore,
    index: usize,
    now: LinkTime,
    out: &mut Vec<u8>,
) {
    let (Some(name), Some(value)) = (store.name(index), store.value(index)) else {
        return;
    };
    let clamp16 = |n: usize| u16::try_from(n).unwrap_or(u16::MAX);
    let message = MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
        param_value: value,
        param_count: clamp16(store.count()),
        param_index: clamp16(index),
        param_id: truncate(name).into(),
        param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
    });
    link.send(&message, now, out);
}

fn send_error(
    link: &mut Link,
    to: Peer,
    name: Option<&ParamName>,
    index: Option<u16>,
    error: MavParamError,
    now: LinkTime,
    out: &mut Vec<u8>,
) {
    let message = MavMessage::PARAM_ERROR(PARAM_ERROR_DATA {
        // -1 says "identified by name" (and an index beyond i16 cannot be a real one either).
        param_index: index.and_then(|i| i16::try_from(i).ok()).unwrap_or(-1),
        target_system: to.system_id,
        target_component: to.component_id,
        param_id: name.map(ParamName::raw).unwrap_or_default().into(),
        error,
    });
    link.send(&message, now, out);
}
