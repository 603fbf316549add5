//! Creating output files: one place that makes the folder, opens the file buffered, and names
//! the path in its error, so every command reports a file it cannot write the same way.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// A file that could not be created, with the path that was asked for.
#[derive(Debug)]
pub struct OutputError {
    pub path: PathBuf,
    pub source: std::io::Error,
}

impl core::fmt::Display for OutputError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.source)
    }
}

impl std::error::Error for OutputError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.source)
    }
}

/// Creates (or truncates) `path` for buffered writing, making its folder first.
pub fn create(path: &Path) -> Result<BufWriter<File>, OutputError> {
    let named = |source| OutputError {
        path: path.to_path_buf(),
        source,
    };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| OutputError {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    File::create(path).map(BufWriter::new).map_err(named)
}

/// Writes `bytes` to `path` whole, through [`create`].
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    use std::io::Write;
    let mut w = create(path)?;
    w.write_all(bytes)
        .and_then(|()| w.flush())
        .map_err(|source| OutputError {
            path: path.to_path_buf(),
            source,
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn creates_the_folder_and_names_the_path_it_cannot_create() {
        let dir = std::env::temp_dir().join(format!("plumbline-output-{}", std::process::id()));
        let path = dir.join("a/b/file.txt");
        let mut w = create(&path).unwrap();
        writeln!(w, "x").unwrap();
        drop(w);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "x\n");
        write(&dir.join("c/whole.txt"), b"y").unwrap();
        assert_eq!(std::fs::read(dir.join("c/whole.txt")).unwrap(), b"y");
        // A file where a folder should be.
        let blocked = path.join("inner.txt");
        let e = create(&blocked).unwrap_err();
        assert!(e.to_string().contains("file.txt"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
