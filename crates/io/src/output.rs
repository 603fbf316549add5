//! Output files that never destroy what they would replace before there is something to replace
//! it with. Every command writes its files through [`OutputFile`]:
//!
//! - [`OutputFile::stage`] creates a hidden file beside the target (`.plumbline-PID-N-NAME`), so an
//!   output that cannot be created fails before any work is done, and the target is untouched.
//! - [`OutputFile::commit`] renames the staged file over the target: results that are only useful
//!   whole (a decoded log, a plot) appear complete or not at all, and a failed run removes the
//!   staged file when it is dropped.
//! - [`OutputFile::publish`] does that rename early, for results that are worth keeping in part:
//!   a recording once the device has sent its first bytes, a trajectory once its first pose is
//!   known. Writing goes on into the same file, so a run killed later keeps what it wrote.
//!
//! [`write`] is the whole-file case: stage, write, commit.
//!
//! [`check_distinct`] refuses outputs that name an input or each other (through symlinks, hard
//! links, `..` or names of files that do not exist yet).

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// A failure naming the file it concerns.
#[derive(Debug)]
pub struct OutputError {
    pub path: String,
    pub message: String,
}

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.path, self.message)
    }
}

impl std::error::Error for OutputError {}

/// An output being written: staged under a hidden name until published or committed.
pub struct OutputFile {
    shown: String,
    target: PathBuf,
    /// The hidden name while the target still holds its old content; `None` once renamed
    /// (or when the target is a device or pipe, which is written in place).
    staged: Option<PathBuf>,
    writer: BufWriter<File>,
}

impl OutputFile {
    /// Creates the staged file (and the target's directory if missing). Fails, naming the path,
    /// when the target cannot be written, so callers stage every output before starting work.
    pub fn stage(path: &Path) -> Result<Self, OutputError> {
        let shown = path.display().to_string();
        let named = |message: String| OutputError {
            path: shown.clone(),
            message,
        };
        // Write through a symlink, as a plain open would: the link keeps pointing at the result.
        let target = match fs::symlink_metadata(path) {
            Ok(m) if m.file_type().is_symlink() => fs::canonicalize(path).unwrap_or(path.into()),
            _ => path.to_path_buf(),
        };
        if target.is_dir() {
            return Err(named("is a directory; give a file name".into()));
        }
        if let Ok(m) = fs::metadata(&target) {
            if !m.is_file() {
                // A device or pipe (/dev/null, a FIFO) cannot be replaced by a rename.
                let file = OpenOptions::new()
                    .write(true)
                    .open(&target)
                    .map_err(|e| named(format!("cannot write: {e}")))?;
                return Ok(Self {
                    shown,
                    target,
                    staged: None,
                    writer: BufWriter::new(file),
                });
            }
        }
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        fs::create_dir_all(&dir).map_err(|e| named(format!("cannot create its directory: {e}")))?;
        let name = target
            .file_name()
            .ok_or_else(|| named("names no file".into()))?
            .to_string_lossy();
        static COUNTER: AtomicU32 = AtomicU32::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let staged = dir.join(format!(".plumbline-{}-{n}-{name}", std::process::id()));
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&staged)
            .map_err(|e| named(format!("cannot create a file in {}: {e}", dir.display())))?;
        if let Ok(old) = fs::metadata(&target) {
            // The replacement keeps the old file's permissions, as an overwrite would.
            let _ = fs::set_permissions(&staged, old.permissions());
        }
        Ok(Self {
            shown,
            target,
            staged: Some(staged),
            writer: BufWriter::new(file),
        })
    }

    /// The path as the user gave it, for messages.
    pub fn shown(&self) -> &str {
        &self.shown
    }

    /// Where the bytes go now: the staged file, or the target once published. For writers that
    /// want a path rather than a stream (the PNG encoder); the name keeps the target's extension.
    pub fn current_path(&self) -> &Path {
        self.staged.as_deref().unwrap_or(&self.target)
    }

    /// Whether the target has been replaced yet.
    pub fn is_published(&self) -> bool {
        self.staged.is_none()
    }

    /// Replaces the target with what has been written so far; later writes go on into it.
    pub fn publish(&mut self) -> Result<(), OutputError> {
        self.flush().map_err(|e| self.error(e))?;
        if let Some(staged) = self.staged.take() {
            if let Err(e) = fs::rename(&staged, &self.target) {
                self.staged = Some(staged);
                return Err(self.error(e));
            }
        }
        Ok(())
    }

    /// Finishes the file: flushed, on disk, and in place of the target.
    pub fn commit(mut self) -> Result<(), OutputError> {
        self.flush().map_err(|e| self.error(e))?;
        self.writer.get_ref().sync_all().or_else(|e| {
            // Devices and pipes cannot be synced; that loses nothing.
            if self.staged.is_none() && !self.target.is_file() {
                Ok(())
            } else {
                Err(self.error(e))
            }
        })?;
        self.publish()
    }

    /// An I/O error on this output, naming it.
    pub fn error(&self, e: io::Error) -> OutputError {
        OutputError {
            path: self.shown.clone(),
            message: e.to_string(),
        }
    }
}

impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.writer.write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.writer.write_all(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.writer.flush()
    }
}

impl Drop for OutputFile {
    /// An output dropped before it was published leaves nothing behind, and the old target as
    /// it was.
    fn drop(&mut self) {
        if let Some(staged) = &self.staged {
            let _ = fs::remove_file(staged);
        }
    }
}

/// Writes `bytes` to `path` whole: the target is replaced only once every byte is on disk.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let mut out = OutputFile::stage(path)?;
    out.write_all(bytes).map_err(|e| out.error(e))?;
    out.commit()
}

/// What a path refers to, for telling whether two paths are one file.
struct Identity {
    /// Device and inode of an existing file: equal for hard links and symlinks.
    inode: Option<(u64, u64)>,
    /// Absolute path with symlinks resolved; for a file that does not exist yet, its
    /// directory's canonical path plus its name.
    canonical: PathBuf,
    /// Character devices (`/dev/null`) hold no data, so naming one twice loses nothing.
    is_char_device: bool,
}

fn identity(path: &Path) -> Identity {
    use std::os::unix::fs::{FileTypeExt, MetadataExt};
    let meta = fs::metadata(path).ok();
    let canonical = fs::canonicalize(path).unwrap_or_else(|_| {
        let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        match (absolute.parent(), absolute.file_name()) {
            (Some(dir), Some(name)) => fs::canonicalize(dir)
                .map(|d| d.join(name))
                .unwrap_or(absolute.clone()),
            _ => absolute,
        }
    });
    Identity {
        inode: meta.as_ref().map(|m| (m.dev(), m.ino())),
        canonical,
        is_char_device: meta.is_some_and(|m| m.file_type().is_char_device()),
    }
}

fn same_file(a: &Identity, b: &Identity) -> bool {
    if a.is_char_device && b.is_char_device {
        return false;
    }
    matches!((a.inode, b.inode), (Some(x), Some(y)) if x == y) || a.canonical == b.canonical
}

/// Refuses outputs that would overwrite an input or another output. Each path comes with the
/// name the user knows it by (`--out`, `LOG`), so the message says which options collide.
pub fn check_distinct(
    inputs: &[(&str, &Path)],
    outputs: &[(&str, &Path)],
) -> Result<(), OutputError> {
    let ins: Vec<_> = inputs.iter().map(|(r, p)| (*r, *p, identity(p))).collect();
    let outs: Vec<_> = outputs.iter().map(|(r, p)| (*r, *p, identity(p))).collect();
    for (k, (role, path, id)) in outs.iter().enumerate() {
        let clash = |what: String| OutputError {
            path: path.display().to_string(),
            message: what,
        };
        if let Some((in_role, _, _)) = ins.iter().find(|(_, _, i)| same_file(i, id)) {
            return Err(clash(format!(
                "{role} names the same file as the input {in_role}; writing it would destroy \
                 the input, so choose another name"
            )));
        }
        if let Some((other, _, _)) = outs[..k].iter().find(|(_, _, o)| same_file(o, id)) {
            return Err(clash(format!(
                "{other} and {role} name the same file; give each output its own name"
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("plumbline-output-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_dropped_output_leaves_the_old_file_and_nothing_else() {
        let d = dir("drop");
        let target = d.join("keep.txt");
        fs::write(&target, "old").unwrap();
        let mut out = OutputFile::stage(&target).unwrap();
        out.write_all(b"new").unwrap();
        drop(out);
        assert_eq!(fs::read_to_string(&target).unwrap(), "old");
        assert_eq!(entries(&d), ["keep.txt"]);
    }

    #[test]
    fn commit_replaces_and_publish_keeps_writing_into_the_target() {
        let d = dir("commit");
        let target = d.join("t.txt");
        fs::write(&target, "old").unwrap();
        let mut out = OutputFile::stage(&target).unwrap();
        out.write_all(b"a").unwrap();
        out.publish().unwrap();
        assert_eq!(fs::read_to_string(&target).unwrap(), "a");
        out.write_all(b"b").unwrap();
        out.flush().unwrap();
        assert_eq!(fs::read_to_string(&target).unwrap(), "ab");
        out.commit().unwrap();
        assert_eq!(entries(&d), ["t.txt"]);
    }

    #[test]
    fn write_creates_the_folder_and_names_the_path_it_cannot_create() {
        let d = dir("write");
        write(&d.join("a/b/whole.txt"), b"y").unwrap();
        assert_eq!(fs::read(d.join("a/b/whole.txt")).unwrap(), b"y");
        // A file where a folder should be.
        let e = write(&d.join("a/b/whole.txt/inner.txt"), b"z").unwrap_err();
        assert!(e.to_string().contains("whole.txt"), "{e}");
        assert_eq!(entries(&d.join("a/b")), ["whole.txt"]);
    }

    #[test]
    fn writing_through_a_symlink_keeps_the_link() {
        let d = dir("symlink");
        let real = d.join("real.txt");
        fs::write(&real, "old").unwrap();
        std::os::unix::fs::symlink(&real, d.join("link.txt")).unwrap();
        let mut out = OutputFile::stage(&d.join("link.txt")).unwrap();
        out.write_all(b"new").unwrap();
        out.commit().unwrap();
        assert!(fs::symlink_metadata(d.join("link.txt"))
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(fs::read_to_string(&real).unwrap(), "new");
    }

    #[test]
    fn aliases_are_found_through_links_dots_and_missing_files() {
        let d = dir("alias");
        let input = d.join("in.log");
        fs::write(&input, "x").unwrap();
        fs::hard_link(&input, d.join("hard.log")).unwrap();
        std::os::unix::fs::symlink(&input, d.join("soft.log")).unwrap();
        fs::create_dir(d.join("sub")).unwrap();
        for alias in ["hard.log", "soft.log", "sub/../in.log"] {
            let err = check_distinct(&[("LOG", &input)], &[("--out", &d.join(alias))]).unwrap_err();
            assert!(err.message.contains("input LOG"), "{alias}: {err}");
        }
        let new = d.join("new.bin");
        let err = check_distinct(
            &[],
            &[("--out", &new), ("--log", &d.join("sub/../new.bin"))],
        )
        .unwrap_err();
        assert!(err.message.contains("--out and --log"), "{err}");
        assert!(check_distinct(&[("LOG", &input)], &[("--out", &new)]).is_ok());
        let null = Path::new("/dev/null");
        assert!(check_distinct(&[], &[("--out", null), ("--log", null)]).is_ok());
    }
}
