//! The command line's capture path (`plumbline lidar decode`): every device's decoder behind the
//! streaming reader, fed in uneven chunks as a file or a port delivers them. No panic, bounded
//! memory, and the same scans and summary however the bytes are split.
#![no_main]
use libfuzzer_sys::fuzz_target;
use plumbline_io::serial::{decode_capture, decode_stream, CaptureError, Device};
use std::io::Read;

/// Hands out at most `chunk` bytes a read.
struct Chunked<'a> {
    data: &'a [u8],
    chunk: usize,
}

impl Read for Chunked<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.data.len().min(buf.len()).min(self.chunk);
        buf[..n].copy_from_slice(&self.data[..n]);
        self.data = &self.data[n..];
        Ok(n)
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&first, bytes)) = data.split_first() else {
        return;
    };
    let device = [Device::Xv11, Device::Xv11Old, Device::Urg, Device::Rplidar][first as usize % 4];
    let whole = decode_capture(device, bytes, 115_200);
    let mut streamed = Vec::new();
    let reader = Chunked {
        data: bytes,
        chunk: 1 + first as usize / 4,
    };
    let summary = decode_stream(device, reader, "fuzz", 115_200, |s| {
        assert_eq!(s.record.ranges_m.len(), s.record.valid.len());
        streamed.push(s);
        Ok::<_, CaptureError>(true)
    });
    match (whole, summary) {
        (Ok((scans, a)), Ok(b)) => {
            assert_eq!(format!("{scans:?}"), format!("{streamed:?}"));
            assert_eq!(a, b);
        }
        (Err(_), Err(_)) => {}
        (a, b) => panic!("whole {:?} vs chunked {:?}", a.map(|x| x.1), b),
    }
});
