//! Opening input files the same way everywhere: gzip recognised by its magic bytes (not by the
//! name), a byte-order mark dropped, lines read with a bounded buffer, and the bytes consumed so
//! far counted for progress bars.

use crate::carmen::ReadError;
use std::cell::Cell;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::rc::Rc;

/// The longest line any reader takes. A CARMEN line with the largest scan the reader accepts
/// (100,000 readings and as many remissions) stays below it; a file without line breaks (a
/// binary file, `/dev/zero`) is refused here instead of being read into memory whole.
pub const MAX_LINE_BYTES: usize = 8 << 20;

/// The first bytes of every gzip member (RFC 1952).
const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// An opened input: its bytes (decompressed when gzip), and how far into the file reading is.
pub struct Input {
    pub name: String,
    pub reader: Box<dyn BufRead>,
    pub progress: ReadProgress,
}

/// Bytes of the file (compressed, when gzip) read so far, against its length when known.
#[derive(Clone)]
pub struct ReadProgress {
    read: Rc<Cell<u64>>,
    pub total: Option<u64>,
}

impl ReadProgress {
    pub fn bytes_read(&self) -> u64 {
        self.read.get()
    }
}

struct Counted<R> {
    inner: R,
    read: Rc<Cell<u64>>,
}

impl<R: Read> Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read.set(self.read.get() + n as u64);
        Ok(n)
    }
}

/// Opens a file for reading, decompressing it when its content is gzip, whatever its name.
pub fn open_input(path: &Path) -> Result<Input, ReadError> {
    let name = path.display().to_string();
    let fail = |message: String| ReadError {
        file: name.clone(),
        line: 0,
        message,
    };
    let file = std::fs::File::open(path).map_err(|e| fail(e.to_string()))?;
    let meta = file.metadata().map_err(|e| fail(e.to_string()))?;
    if meta.is_dir() {
        return Err(fail("is a directory, not a file".into()));
    }
    let read = Rc::new(Cell::new(0));
    let mut raw = BufReader::with_capacity(
        64 << 10,
        Counted {
            inner: file,
            read: read.clone(),
        },
    );
    let head = raw
        .fill_buf()
        .map_err(|e| fail(format!("cannot read: {e}")))?;
    let reader: Box<dyn BufRead> = if head.starts_with(&GZIP_MAGIC) {
        Box::new(BufReader::new(flate2::read::MultiGzDecoder::new(raw)))
    } else {
        Box::new(raw)
    };
    Ok(Input {
        name,
        reader,
        progress: ReadProgress {
            read,
            total: meta.is_file().then_some(meta.len()),
        },
    })
}

/// The largest whole text file [`read_text`] takes: far beyond any world, vehicle or map YAML.
pub const MAX_TEXT_FILE_BYTES: u64 = 64 << 20;

/// Reads a small text file whole (a world, a vehicle, a map's YAML): gzip by content, a
/// byte-order mark dropped, and anything that is not UTF-8 text refused with where it stops.
pub fn read_text(path: &Path) -> Result<String, ReadError> {
    let input = open_input(path)?;
    let fail = |message: String| ReadError {
        file: input.name.clone(),
        line: 0,
        message,
    };
    let mut bytes = Vec::new();
    input
        .reader
        .take(MAX_TEXT_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| fail(format!("cannot read: {e}")))?;
    if bytes.len() as u64 > MAX_TEXT_FILE_BYTES {
        return Err(fail(format!(
            "larger than {} MiB: not the small text file expected here",
            MAX_TEXT_FILE_BYTES >> 20
        )));
    }
    let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes);
    match std::str::from_utf8(body) {
        Ok(text) => Ok(text.to_string()),
        Err(e) => {
            let before = &body[..e.valid_up_to()];
            let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
            Err(ReadError {
                file: input.name.clone(),
                line,
                message: "not text: invalid UTF-8 (a binary file?)".into(),
            })
        }
    }
}

/// Lines of a text file, numbered from 1, each at most [`MAX_LINE_BYTES`], the UTF-8
/// byte-order mark some editors put in front of the first line removed.
pub struct TextLines<R> {
    reader: R,
    name: String,
    line: usize,
    buf: Vec<u8>,
}

impl<R: BufRead> TextLines<R> {
    pub fn new(reader: R, name: &str) -> Self {
        Self {
            reader,
            name: name.to_string(),
            line: 0,
            buf: Vec::new(),
        }
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The number of the line last returned.
    pub fn line_no(&self) -> usize {
        self.line
    }

    /// An error at the line last returned.
    pub fn error(&self, message: String) -> ReadError {
        ReadError {
            file: self.name.clone(),
            line: self.line,
            message,
        }
    }

    /// The next line, numbered, without its line ending; `None` at the end of the file.
    pub fn next_line(&mut self) -> Result<Option<(usize, &str)>, ReadError> {
        self.buf.clear();
        self.line += 1;
        let limit = MAX_LINE_BYTES as u64 + 1;
        let n = (&mut self.reader)
            .take(limit)
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| self.error(format!("cannot read: {e}")))?;
        if n == 0 {
            return Ok(None);
        }
        if self.buf.len() > MAX_LINE_BYTES && !self.buf.ends_with(b"\n") {
            return Err(self.error(format!(
                "line is longer than {} MiB: this does not look like a text file",
                MAX_LINE_BYTES >> 20
            )));
        }
        let mut bytes = &self.buf[..];
        if self.line == 1 {
            bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        }
        bytes = bytes.strip_suffix(b"\n").unwrap_or(bytes);
        bytes = bytes.strip_suffix(b"\r").unwrap_or(bytes);
        match std::str::from_utf8(bytes) {
            Ok(text) => Ok(Some((self.line, text))),
            Err(e) => Err(ReadError {
                file: self.name.clone(),
                line: self.line,
                message: format!(
                    "not text: invalid UTF-8 at byte {} of the line (a binary file?)",
                    e.valid_up_to() + 1
                ),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(bytes: &[u8]) -> Result<Vec<String>, ReadError> {
        let mut t = TextLines::new(bytes, "t");
        let mut out = Vec::new();
        while let Some((_, l)) = t.next_line()? {
            out.push(l.to_string());
        }
        Ok(out)
    }

    #[test]
    fn bom_and_line_endings_are_dropped() {
        assert_eq!(
            lines(b"\xEF\xBB\xBFa b\r\nc\n\xEF\xBB\xBFd").unwrap(),
            ["a b", "c", "\u{feff}d"]
        );
    }

    #[test]
    fn a_line_without_end_is_refused_with_bounded_memory() {
        let zeros = std::io::repeat(b'0').take(MAX_LINE_BYTES as u64 * 3);
        let mut t = TextLines::new(BufReader::new(zeros), "zeros");
        let err = t.next_line().unwrap_err();
        assert_eq!(err.line, 1);
        assert!(err.message.contains("longer than 8 MiB"), "{err}");
        assert!(t.buf.capacity() <= 2 * MAX_LINE_BYTES + 64);
    }

    #[test]
    fn whole_text_drops_the_mark_and_names_the_line_of_bad_bytes() {
        let path = std::env::temp_dir().join(format!("plumbline-text-{}", std::process::id()));
        std::fs::write(&path, b"\xEF\xBB\xBFstart 0 0 0\n").unwrap();
        assert_eq!(read_text(&path).unwrap(), "start 0 0 0\n");
        std::fs::write(&path, b"a\nb\xFF\n").unwrap();
        let err = read_text(&path).unwrap_err();
        assert_eq!(err.line, 2, "{err}");
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn gzip_is_found_by_its_content() {
        use std::io::Write;
        let path = std::env::temp_dir().join(format!("plumbline-gz-{}.txt", std::process::id()));
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        gz.write_all(b"hello\n").unwrap();
        std::fs::write(&path, gz.finish().unwrap()).unwrap();
        let input = open_input(&path).unwrap();
        assert_eq!(lines_of(input), ["hello"]);
        std::fs::remove_file(&path).unwrap();
    }

    fn lines_of(input: Input) -> Vec<String> {
        let mut t = TextLines::new(input.reader, &input.name);
        let mut out = Vec::new();
        while let Some((_, l)) = t.next_line().unwrap() {
            out.push(l.to_string());
        }
        out
    }
}
