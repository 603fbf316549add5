//! The replies of the parameter protocol, from the caller's [`ParameterStore`].

use crate::link::{Link, LinkTime, Peer};
use crate::params::{truncate, ParamName, ParamRef, ParamRequest, ParameterStore};
use mavlink::dialects::common::{
    MavMessage, MavParamError, MavParamType, MavSeverity, PARAM_ERROR_DATA, PARAM_VALUE_DATA,
};
use plumbline_core::flight::params::ParamError;

/// Where the replies to one request go.
struct Replies<'a> {
    link: &'a mut Link,
    to: Peer,
    now: LinkTime,
    out: &'a mut Vec<u8>,
}

pub(crate) fn serve(
    link: &mut Link,
    request: &ParamRequest,
    from: Peer,
    store: &mut dyn ParameterStore,
    now: LinkTime,
    out: &mut Vec<u8>,
) {
    let mut reply = Replies {
        link,
        to: from,
        now,
        out,
    };
    let which = match *request {
        ParamRequest::List => {
            for index in 0..store.count() {
                reply.value(store, index);
            }
            return;
        }
        ParamRequest::Read(which) => which,
        ParamRequest::Set { name, .. } => ParamRef::Name(name),
    };
    let Some(index) = lookup(store, &which) else {
        return reply.error(&which, MavParamError::MAV_PARAM_ERROR_DOES_NOT_EXIST);
    };
    let ParamRequest::Set { name, value } = *request else {
        return reply.value(store, index);
    };
    match store.set(index, value) {
        Ok(_) => reply.value(store, index),
        Err(refusal) => {
            reply.error(&which, param_error(&refusal));
            reply.value(store, index);
            let text = format!("{} {value}: {refusal}", name.as_str().unwrap_or_default());
            let Replies { link, now, out, .. } = reply;
            link.statustext(MavSeverity::MAV_SEVERITY_WARNING, &text, now, out);
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

fn lookup(store: &dyn ParameterStore, which: &ParamRef) -> Option<usize> {
    match which {
        ParamRef::Index(i) => Some(usize::from(*i)).filter(|&i| i < store.count()),
        ParamRef::Name(name) => name.as_str().and_then(|n| store.index_of(n)),
    }
}

impl Replies<'_> {
    fn value(&mut self, store: &dyn ParameterStore, index: usize) {
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
        self.link.send(&message, self.now, self.out);
    }

    fn error(&mut self, which: &ParamRef, error: MavParamError) {
        let (param_index, param_id) = match which {
            // An index beyond i16 cannot be a real one; -1 then says "see the name" (empty).
            ParamRef::Index(i) => (i16::try_from(*i).unwrap_or(-1), [0; 16]),
            ParamRef::Name(name) => (-1, ParamName::raw(name)),
        };
        let message = MavMessage::PARAM_ERROR(PARAM_ERROR_DATA {
            param_index,
            target_system: self.to.system_id,
            target_component: self.to.component_id,
            param_id: param_id.into(),
            error,
        });
        self.link.send(&message, self.now, self.out);
    }
}
