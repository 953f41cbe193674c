//! Atomic file output for every writer (PNG, MP4, JSON, CSV, glb, the bake cache).
//!
//! The bytes go to a uniquely named temporary file in the target's folder, so that the final
//! rename stays on one file system; they are synced to disk and replace the target in one
//! rename. A reader never sees half a file, and two runs writing the same output never trip
//! over one temporary name. A run stopped by Ctrl-C or SIGTERM removes its temporary files on
//! the way out. A run killed outright (SIGKILL, a crash) cannot: its temporary files carry its
//! process id, and the next writer of the same target removes those whose process is gone. A
//! target that is not a plain file (a FIFO, a socket, a device, a symbolic link or a folder) is
//! refused: renaming over it would replace something the user made.

use anyhow::{Context, Result, anyhow, bail};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Temporary files being written now: what an interrupted run removes.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The folder `path` goes into (`.` for a bare file name).
fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Fails, before any work is done, if `path` cannot take a file: its folder is missing, or it
/// exists as something other than a plain file.
pub fn check_target(path: &Path) -> Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(meta) => {
            let kind = meta.file_type();
            if kind.is_symlink() {
                bail!("{}: cannot write: is a symbolic link", path.display());
            }
            if kind.is_dir() {
                bail!("{}: cannot write: is a folder", path.display());
            }
            if !kind.is_file() {
                bail!(
                    "{}: cannot write: not a plain file (a FIFO, socket or device)",
                    path.display()
                );
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => bail!("{}: cannot write: {e}", path.display()),
    }
    let parent = folder(path);
    if !parent.is_dir() {
        bail!(
            "{}: cannot write: folder {} does not exist",
            path.display(),
            parent.display()
        );
    }
    Ok(())
}

/// Makes `dir` (and the folders above it) for a command's outputs, failing with what is in the
/// way: something there that is not a folder (a file, a device such as `/dev/full`), a
/// permission, a read-only or full disk.
pub fn make_folder(dir: &Path) -> Result<()> {
    if let Ok(meta) = std::fs::metadata(dir)
        && !meta.is_dir()
    {
        let what = if meta.is_file() {
            "a file"
        } else {
            "a device, FIFO or socket"
        };
        bail!(
            "{}: cannot write into it: it is {what}, not a folder",
            dir.display()
        );
    }
    std::fs::create_dir_all(dir).map_err(|e| {
        let why = match e.kind() {
            std::io::ErrorKind::PermissionDenied => "permission denied".to_string(),
            std::io::ErrorKind::ReadOnlyFilesystem => "the file system is read-only".into(),
            std::io::ErrorKind::StorageFull => "the disk is full".into(),
            std::io::ErrorKind::NotADirectory => {
                "a file stands where a folder above it goes".into()
            }
            _ => e.to_string(),
        };
        anyhow!("{}: cannot create the folder: {why}", dir.display())
    })
}

/// A page gets no signals: the web build has nothing to clean up on one.
#[cfg(target_arch = "wasm32")]
pub fn remove_pending_on_interrupt() {}

/// On Ctrl-C or SIGTERM, removes the temporary files being written, says so in one line (on a
/// line of its own where a progress bar may have been drawing on the terminal) and exits with
/// 130. `lodlab` installs it first thing; a library user's first file being written installs
/// it too, unless the program has a handler of its own.
#[cfg(not(target_arch = "wasm32"))]
pub fn remove_pending_on_interrupt() {
    static INSTALL: std::sync::Once = std::sync::Once::new();
    INSTALL.call_once(|| {
        // Another handler already installed (a host program's) keeps its say.
        let _ = ctrlc::set_handler(|| {
            let mut removed = 0;
            if let Ok(pending) = PENDING.lock() {
                for p in pending.iter() {
                    removed += std::fs::remove_file(p).is_ok() as usize;
                }
            }
            use std::io::{IsTerminal, Write};
            let mut err = std::io::stderr();
            let _ = writeln!(
                err,
                "{}lodlab: interrupted{}",
                if err.is_terminal() { "\n" } else { "" },
                match removed {
                    0 => String::new(),
                    n => format!(
                        "; {n} unfinished file{} removed",
                        if n == 1 { "" } else { "s" }
                    ),
                }
            );
            std::process::exit(130);
        });
    });
}

/// A file being written: a temporary file beside the target that [`AtomicFile::commit`]
/// moves into place. Dropped uncommitted (an error, a panic), it leaves nothing behind.
pub struct AtomicFile {
    temp: Option<tempfile::NamedTempFile>,
    target: PathBuf,
}

impl AtomicFile {
    pub fn create(target: &Path) -> Result<AtomicFile> {
        // A page has no files to write (the browser's own downloads are another matter).
        if cfg!(target_arch = "wasm32") {
            bail!("{}: the web viewer writes no files", target.display());
        }
        check_target(target)?;
        remove_pending_on_interrupt();
        let name = target
            .file_name()
            .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
        remove_stale(folder(target), &name);
        let temp = tempfile::Builder::new()
            .prefix(&format!(".{name}.{}.", std::process::id()))
            .suffix(".tmp")
            .tempfile_in(folder(target))
            .with_context(|| format!("{}: cannot write", target.display()))?;
        PENDING
            .lock()
            .map_err(|_| anyhow!("{}: cannot write: a writer panicked", target.display()))?
            .push(temp.path().to_path_buf());
        Ok(AtomicFile {
            temp: Some(temp),
            target: target.to_path_buf(),
        })
    }

    /// The file to write to.
    pub fn file(&mut self) -> &mut File {
        self.temp
            .as_mut()
            .expect("present until committed")
            .as_file_mut()
    }

    /// A second handle on the file, for writers that must own theirs.
    pub fn handle(&self) -> std::io::Result<File> {
        self.temp
            .as_ref()
            .expect("present until committed")
            .as_file()
            .try_clone()
    }

    /// The temporary file's path, for writers that take a path.
    pub fn temp_path(&self) -> &Path {
        self.temp.as_ref().expect("present until committed").path()
    }

    /// Syncs the file and renames it over the target.
    pub fn commit(mut self) -> Result<()> {
        let temp = self.temp.take().expect("present until committed");
        let target = self.target.clone();
        let fail = |e: &dyn std::fmt::Display| anyhow!("{}: cannot write: {e}", target.display());
        temp.as_file().sync_all().map_err(|e| fail(&e))?;
        // Readable as a file made by `File::create` would be (the temporary one is private).
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let _ = std::fs::set_permissions(temp.path(), std::fs::Permissions::from_mode(0o644));
        }
        // What is there may have changed while the file was written.
        check_target(&target)?;
        let path = temp.path().to_path_buf();
        let result = temp.persist(&target).map(drop).map_err(|e| fail(&e.error));
        forget_pending(&path);
        result
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(temp) = self.temp.take() {
            let path = temp.path().to_path_buf();
            drop(temp);
            forget_pending(&path);
        }
    }
}

/// Is process `pid` still running? Where that cannot be known, a file older than a day
/// counts as abandoned instead.
fn alive(pid: u32, modified: Option<std::time::SystemTime>) -> bool {
    let proc = Path::new("/proc");
    if proc.join("self").exists() {
        // A killed process not yet reaped by its parent is a zombie: gone for this purpose.
        return std::fs::read_to_string(proc.join(pid.to_string()).join("stat"))
            .ok()
            .and_then(|stat| {
                let state = stat.rsplit_once(')')?.1.trim_start().chars().next()?;
                Some(!matches!(state, 'Z' | 'X'))
            })
            .unwrap_or(false);
    }
    modified
        .and_then(|m| m.elapsed().ok())
        .is_none_or(|age| age.as_secs() < 24 * 3600)
}

/// Removes the temporary files of `name` in `folder` left by runs that were killed before they
/// could (`.NAME.PID.XXXXXX.tmp` whose process is gone). Another live run's are kept.
fn remove_stale(folder: &Path, name: &str) {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    let prefix = format!(".{name}.");
    for entry in entries.flatten() {
        let file = entry.file_name();
        let Some(rest) = file
            .to_str()
            .and_then(|f| f.strip_prefix(&prefix))
            .filter(|r| r.ends_with(".tmp"))
        else {
            continue;
        };
        let Some(pid) = rest.split('.').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        let modified = entry.metadata().ok().and_then(|m| m.modified().ok());
        if pid != std::process::id() && !alive(pid, modified) {
            match std::fs::remove_file(entry.path()) {
                Ok(()) => log::info!(
                    "removed {}, left by a run that was killed",
                    entry.path().display()
                ),
                Err(e) => log::debug!("could not remove {}: {e}", entry.path().display()),
            }
        }
    }
}

fn forget_pending(path: &Path) {
    if let Ok(mut pending) = PENDING.lock() {
        pending.retain(|p| p != path);
    }
}

/// Writes `bytes` to `path` atomically.
pub fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.file()
        .write_all(bytes)
        .with_context(|| format!("{}: cannot write", path.display()))?;
    file.commit()
}

/// Writes `image` to `path` as a PNG, atomically.
pub fn write_png(path: &Path, image: &image::RgbaImage) -> Result<()> {
    let mut bytes = Vec::new();
    image
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .with_context(|| format!("{}: cannot encode the PNG", path.display()))?;
    write(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_replace_the_target_and_leave_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.json");
        write(&out, b"one").unwrap();
        write(&out, b"two").unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"two");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "only the target is left");
        // Other tests write at the same time: none of this one's files is still pending.
        let pending = PENDING.lock().unwrap();
        assert!(
            pending.iter().all(|p| !p.starts_with(dir.path())),
            "{pending:?}"
        );
    }

    #[test]
    fn an_uncommitted_file_leaves_nothing_and_keeps_the_old_one() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("b.png");
        write(&out, b"old").unwrap();
        {
            let mut f = AtomicFile::create(&out).unwrap();
            f.file().write_all(b"half").unwrap();
            assert!(f.temp_path().exists());
        }
        assert_eq!(std::fs::read(&out).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn two_writers_of_one_target_do_not_collide() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("c.csv");
        let mut a = AtomicFile::create(&out).unwrap();
        let mut b = AtomicFile::create(&out).unwrap();
        assert_ne!(a.temp_path(), b.temp_path());
        a.file().write_all(b"a").unwrap();
        b.file().write_all(b"b").unwrap();
        a.commit().unwrap();
        b.commit().unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"b");
    }

    #[test]
    fn a_killed_runs_temporary_files_go_at_the_next_write() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("clip.mp4");
        // A process id no system hands out (Linux stops at 2²²), and this process's own.
        let stale = dir.path().join(".clip.mp4.999999999.a1b2c3.tmp");
        let live = dir
            .path()
            .join(format!(".clip.mp4.{}.d4e5f6.tmp", std::process::id()));
        let other = dir.path().join(".other.png.999999999.a1b2c3.tmp");
        for p in [&stale, &live, &other] {
            std::fs::write(p, b"half").unwrap();
        }
        write(&out, b"whole").unwrap();
        if Path::new("/proc/self").exists() {
            assert!(!stale.exists(), "the dead run's file is removed");
        }
        assert!(live.exists(), "a live run's file is kept");
        assert!(other.exists(), "another target's files are left alone");
        assert_eq!(std::fs::read(&out).unwrap(), b"whole");
    }

    #[cfg(unix)]
    #[test]
    fn special_files_and_links_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("real.txt");
        std::fs::write(&target, b"mine").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let e = write(&link, b"x").unwrap_err().to_string();
        assert!(e.contains("symbolic link") && e.contains("link.txt"), "{e}");
        assert_eq!(std::fs::read(&target).unwrap(), b"mine");
        let e = write(Path::new("/dev/null"), b"x").unwrap_err().to_string();
        assert!(e.contains("not a plain file"), "{e}");
        let e = write(dir.path(), b"x").unwrap_err().to_string();
        assert!(e.contains("is a folder"), "{e}");
        let e = write(&dir.path().join("no/such/x.png"), b"x")
            .unwrap_err()
            .to_string();
        assert!(e.contains("does not exist"), "{e}");
    }
}
