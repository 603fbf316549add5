//! The g2o reader on arbitrary bytes: it must return a graph or an error, never panic, and a
//! graph it accepts must survive being written and read again unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use plumbline_slam::graph::{read_g2o, write_g2o, NodeId};

fuzz_target!(|data: &[u8]| {
    let Ok(graph) = read_g2o(data) else { return };
    let mut text = Vec::new();
    write_g2o(&graph, &mut text).expect("writing to memory cannot fail");
    let back = read_g2o(text.as_slice()).expect("a written graph reads back");
    assert_eq!(back.nodes(), graph.nodes());
    assert_eq!(back.edges(), graph.edges());
    for k in 0..graph.nodes().len() as u32 {
        assert_eq!(back.is_fixed(NodeId(k)), graph.is_fixed(NodeId(k)));
    }
});
