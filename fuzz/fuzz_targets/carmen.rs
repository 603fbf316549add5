//! CARMEN log reader, the streaming path the commands use: arbitrary text is records or an
//! error naming a line, never a panic, and reading record by record agrees with reading whole.
#![no_main]
use libfuzzer_sys::fuzz_target;
use plumbline_io::carmen::{parse_log, LogItem, LogReader, ReadOptions};

fuzz_target!(|data: &[u8]| {
    for skip_bad_lines in [false, true] {
        let opts = ReadOptions {
            skip_bad_lines,
            ..ReadOptions::default()
        };
        let mut reader = LogReader::new(data, "fuzz", &opts);
        let mut scans = Vec::new();
        let streamed = loop {
            match reader.next_item() {
                Ok(Some(LogItem::Scan(s))) => {
                    assert_eq!(s.ranges_m.len(), s.valid.len());
                    scans.push(s);
                }
                Ok(Some(_)) => {}
                Ok(None) => break Ok(()),
                Err(e) => break Err(e),
            }
        };
        match (parse_log(data, "fuzz", &opts), streamed) {
            (Ok(log), Ok(())) => {
                assert_eq!(format!("{:?}", log.scans), format!("{scans:?}"));
                assert_eq!(&log.stats, reader.stats());
            }
            (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
            (a, b) => panic!("whole {:?} vs streamed {:?}", a.map(|l| l.stats), b),
        }
    }
});
