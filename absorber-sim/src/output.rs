//! The one output writer of every command: files that cannot tear or lie.
//!
//! - Every file is written under a hidden temporary name beside its target
//!   (`.host-sim-partial-…`) and renamed into place only when the command completed.
//! - Commands that produce a set of files (`run`, `sweep`, `fatigue`) write a manifest last,
//!   `<name>.manifest.json`: what ran, its status, its files (with their sizes). A failed run
//!   writes a manifest with `"status": "failed"`, the error, no files of its own, and keeps the
//!   previous complete result (its files stay, listed under `"previous"`). An interrupted run
//!   leaves the previous files and manifest as they were, plus hidden partial files that the next
//!   run into the directory removes. While files are renamed the manifest says `"committing"`.
//! - Files listed by the previous manifest of the same name that the new run does not produce
//!   are removed, so a rerun with fewer plots leaves no stale figure beside the new result.
//! - One command at a time writes into a directory: the lock file `.host-sim.lock` is held from
//!   the start of the command to its end; a second command waits (and says so on stderr).
//! - The directory is created and checked writable before any computation; write errors name
//!   the file.

use anyhow::{anyhow, bail, Context, Result};
use fs4::fs_std::FileExt;
use serde_json::{json, Value};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use tempfile::{NamedTempFile, TempPath};

/// Name of the lock file in an output directory.
pub const LOCK_FILE: &str = ".host-sim.lock";
/// Prefix of the temporary files (hidden; removed by the next command into the directory).
pub const PARTIAL_PREFIX: &str = ".host-sim-partial-";

/// Status written into a manifest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Every part of the command succeeded.
    Complete,
    /// The files are complete, but some points (runs) failed; they are marked in the files.
    PointsFailed,
}

impl Status {
    /// The status of a study of several points (runs), `failed` of which failed.
    pub fn of_points(failed: usize) -> Self {
        if failed > 0 {
            Status::PointsFailed
        } else {
            Status::Complete
        }
    }

    fn name(self) -> &'static str {
        match self {
            Status::Complete => "complete",
            Status::PointsFailed => "points-failed",
        }
    }
}

/// An output directory held by one command (see the module documentation).
pub struct OutputDir {
    dir: PathBuf,
    manifest: Option<String>,
    what: String,
    staged: Vec<(PathBuf, TempPath)>,
    previous: Option<Value>,
    started: String,
    _lock: File,
}

/// A file being streamed; [`OutputDir::finish`] stages it. Dropped without it, nothing appears.
pub struct StreamFile {
    target: PathBuf,
    w: BufWriter<NamedTempFile>,
}

impl StreamFile {
    /// Writes one line (a newline is added); the error names the file.
    pub fn line(&mut self, s: &str) -> Result<()> {
        writeln!(self.w, "{s}").map_err(|e| write_error(&self.target, &e))
    }

    /// Writes text as is; the error names the file.
    pub fn text(&mut self, s: &str) -> Result<()> {
        self.w
            .write_all(s.as_bytes())
            .map_err(|e| write_error(&self.target, &e))
    }

    /// The final path.
    pub fn target(&self) -> &Path {
        &self.target
    }
}

/// Temporary files get the mode of an ordinary new file (rw-r--r--), not tempfile's private
/// 0600, since they become the outputs.
fn builder() -> tempfile::Builder<'static, 'static> {
    let mut b = tempfile::Builder::new();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(0o644));
    }
    b
}

fn write_error(path: &Path, e: &std::io::Error) -> anyhow::Error {
    anyhow!("cannot write `{}`: {e}", path.display())
}

fn now() -> String {
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0);
    format!("{t:.3}")
}

impl OutputDir {
    /// Creates `dir` if needed, checks that it is writable, takes its lock (waiting for another
    /// command that holds it) and removes partial files left by an interrupted command.
    /// `manifest`: the manifest's name (`<manifest>.manifest.json`), or `None` for commands that
    /// write one document (the docs/ generators). `what`: the command line, for the manifest.
    pub fn open(dir: &Path, manifest: Option<&str>, what: &str) -> Result<Self> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create output directory `{}`", dir.display()))?;
        // Writable? (before any computation)
        let probe = tempfile::Builder::new()
            .prefix(PARTIAL_PREFIX)
            .tempfile_in(dir)
            .map_err(|e| anyhow!("output directory `{}` is not writable: {e}", dir.display()))?;
        drop(probe);
        let lock_path = dir.join(LOCK_FILE);
        let lock = File::options()
            .create(true)
            .truncate(false)
            .read(true)
            .write(true)
            .open(&lock_path)
            .with_context(|| format!("cannot open lock file `{}`", lock_path.display()))?;
        let got = lock
            .try_lock_exclusive()
            .with_context(|| format!("cannot lock `{}`", lock_path.display()))?;
        if !got {
            eprintln!(
                "waiting: another host-sim command is writing into `{}` (lock file `{}`); \
                 this one starts when it ends",
                dir.display(),
                lock_path.display()
            );
            lock.lock_exclusive()
                .with_context(|| format!("cannot lock `{}`", lock_path.display()))?;
        }
        // Under the lock nobody else writes here: partial files are leftovers of an
        // interrupted command.
        if let Ok(entries) = std::fs::read_dir(dir) {
            for e in entries.flatten() {
                if e.file_name().to_string_lossy().starts_with(PARTIAL_PREFIX) {
                    let _ = std::fs::remove_file(e.path());
                }
            }
        }
        let mut out = Self {
            dir: dir.to_path_buf(),
            manifest: manifest.map(str::to_string),
            what: what.to_string(),
            staged: Vec::new(),
            previous: None,
            started: now(),
            _lock: lock,
        };
        out.previous = out.read_manifest();
        Ok(out)
    }

    /// Opens the directory of one document `path` (its parent; `.` for a bare name), without a
    /// manifest; returns it and the document's file name.
    pub fn for_file(path: &Path, what: &str) -> Result<(Self, String)> {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        Ok((Self::open(&dir, None, what)?, name))
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    fn manifest_path(&self) -> Option<PathBuf> {
        self.manifest
            .as_ref()
            .map(|m| self.dir.join(format!("{m}.manifest.json")))
    }

    fn read_manifest(&self) -> Option<Value> {
        let p = self.manifest_path()?;
        let text = std::fs::read_to_string(p).ok()?;
        serde_json::from_str(&text).ok()
    }

    fn target(&self, name: &str) -> Result<PathBuf> {
        if name.is_empty()
            || name.contains(['/', '\\'])
            || name.starts_with('.')
            || name.ends_with(".manifest.json")
        {
            bail!("invalid output file name `{name}`");
        }
        Ok(self.dir.join(name))
    }

    fn temp(&self, name: &str) -> Result<NamedTempFile> {
        // Keep the extension last: the PNG encoder picks the format from it.
        let ext = Path::new(name)
            .extension()
            .map(|e| format!(".{}", e.to_string_lossy()))
            .unwrap_or_default();
        builder()
            .prefix(&format!("{PARTIAL_PREFIX}{name}-"))
            .suffix(&ext)
            .tempfile_in(&self.dir)
            .map_err(|e| anyhow!("cannot create a file in `{}`: {e}", self.dir.display()))
    }

    /// Starts streaming the file `name` (in the directory).
    pub fn stream(&self, name: &str) -> Result<StreamFile> {
        let target = self.target(name)?;
        let tmp = self.temp(name)?;
        Ok(StreamFile {
            target,
            w: BufWriter::with_capacity(1 << 16, tmp),
        })
    }

    /// Flushes a streamed file to disk and stages it; returns its final path.
    pub fn finish(&mut self, f: StreamFile) -> Result<PathBuf> {
        let StreamFile { target, w } = f;
        let tmp = w
            .into_inner()
            .map_err(|e| write_error(&target, e.error()))?;
        tmp.as_file()
            .sync_all()
            .map_err(|e| write_error(&target, &e))?;
        self.staged.push((target.clone(), tmp.into_temp_path()));
        Ok(target)
    }

    /// Writes the whole file `name` and stages it.
    pub fn write(&mut self, name: &str, content: &str) -> Result<PathBuf> {
        let mut f = self.stream(name)?;
        f.text(content)?;
        self.finish(f)
    }

    /// Lets `produce` write the file `name` at the temporary path it is given (for libraries
    /// that take a path, e.g. the PNG encoder), then stages it.
    pub fn write_with(
        &mut self,
        name: &str,
        produce: impl FnOnce(&Path) -> Result<()>,
    ) -> Result<PathBuf> {
        let target = self.target(name)?;
        let tmp = self.temp(name)?.into_temp_path();
        produce(&tmp).with_context(|| format!("cannot write `{}`", target.display()))?;
        File::open(&tmp)
            .and_then(|f| f.sync_all())
            .map_err(|e| write_error(&target, &e))?;
        self.staged.push((target.clone(), tmp));
        Ok(target)
    }

    fn write_manifest(&self, v: &Value) -> Result<()> {
        let Some(path) = self.manifest_path() else {
            return Ok(());
        };
        let text = serde_json::to_string_pretty(v)? + "\n";
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        let mut tmp = self.temp(&name)?;
        tmp.write_all(text.as_bytes())
            .and_then(|_| tmp.as_file().sync_all())
            .map_err(|e| write_error(&path, &e))?;
        tmp.persist(&path)
            .map_err(|e| anyhow!("cannot write `{}`: {}", path.display(), e.error))?;
        Ok(())
    }

    /// The last complete result recorded in the previous manifest (itself if complete, else
    /// the one it kept).
    fn previous_complete(&self) -> Value {
        match &self.previous {
            Some(p) if p.get("status").and_then(Value::as_str) != Some("failed") => {
                if p.get("status").and_then(Value::as_str) == Some("committing") {
                    Value::Null
                } else {
                    p.clone()
                }
            }
            Some(p) => p.get("previous").cloned().unwrap_or(Value::Null),
            None => Value::Null,
        }
    }

    fn file_names(v: &Value) -> Vec<String> {
        v.get("files")
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .filter_map(|f| f.get("name").and_then(Value::as_str))
                    .map(str::to_string)
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Renames every staged file into place, then writes the manifest (status, files, `extra`)
    /// and removes the files of the previous manifest that this run did not produce.
    pub fn commit(mut self, status: Status, extra: Value) -> Result<Vec<PathBuf>> {
        let names: Vec<String> = self
            .staged
            .iter()
            .filter_map(|(t, _)| t.file_name().map(|n| n.to_string_lossy().to_string()))
            .collect();
        self.write_manifest(&json!({
            "command": self.what,
            "status": "committing",
            "note": "files are being renamed into place; if this stays, the run was interrupted and the files are not a consistent set",
            "files": names.iter().map(|n| json!({ "name": n })).collect::<Vec<_>>(),
        }))?;
        let mut files = Vec::new();
        let mut listed = Vec::new();
        for (target, tmp) in std::mem::take(&mut self.staged) {
            tmp.persist(&target)
                .map_err(|e| anyhow!("cannot write `{}`: {}", target.display(), e.error))?;
            let bytes = std::fs::metadata(&target).map(|m| m.len()).unwrap_or(0);
            let name = target
                .file_name()
                .map(|n| n.to_string_lossy().to_string())
                .unwrap_or_default();
            listed.push(json!({ "name": name, "bytes": bytes }));
            files.push(target);
        }
        let old = Self::file_names(&self.previous_complete());
        let mut removed = Vec::new();
        for n in old {
            if !names.contains(&n) && self.target(&n).is_ok() {
                let p = self.dir.join(&n);
                if std::fs::remove_file(&p).is_ok() {
                    removed.push(n);
                }
            }
        }
        self.write_manifest(&json!({
            "command": self.what,
            "status": status.name(),
            "started": self.started,
            "finished": now(),
            "host_sim": env!("CARGO_PKG_VERSION"),
            "files": listed,
            "removed_stale": removed,
            "result": extra,
        }))?;
        Ok(files)
    }

    /// Records a failed command: the manifest says `failed` with the error and keeps the
    /// previous complete result (whose files stay). Staged files are discarded.
    pub fn fail(mut self, error: &anyhow::Error) -> Result<()> {
        self.staged.clear();
        let prev = self.previous_complete();
        self.write_manifest(&json!({
            "command": self.what,
            "status": "failed",
            "started": self.started,
            "finished": now(),
            "error": format!("{error:#}"),
            "files": [],
            "previous": prev,
        }))
    }
}

/// Runs `body` with an open output directory; on success commits what it staged with the
/// status and summary it returns, on failure records the failure (the error is returned).
pub fn with_output<T>(
    mut out: OutputDir,
    body: impl FnOnce(&mut OutputDir) -> Result<(T, Status, Value)>,
) -> Result<(T, Vec<PathBuf>)> {
    match body(&mut out) {
        Ok((t, status, extra)) => {
            let files = out.commit(status, extra)?;
            Ok((t, files))
        }
        Err(e) => {
            if let Err(m) = out.fail(&e) {
                return Err(e.context(format!("(and the failure could not be recorded: {m:#})")));
            }
            Err(e)
        }
    }
}

/// The command line as one string (for manifests).
pub fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

/// Error of a command that completed and wrote its outputs but some of whose points (runs)
/// failed; the process exits with [`EXIT_POINTS_FAILED`].
#[derive(Debug)]
pub struct PointsFailed(pub String);

impl std::fmt::Display for PointsFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PointsFailed {}

/// Exit code: the command completed, but some points failed (marked in its outputs).
pub const EXIT_POINTS_FAILED: u8 = 3;

/// Writes one file atomically (temporary file beside it, renamed into place), without a lock:
/// for caches shared by the threads of one command. The error names the file.
pub fn atomic_write(path: &Path, content: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create directory `{}`", dir.display()))?;
    let mut tmp = builder()
        .prefix(PARTIAL_PREFIX)
        .tempfile_in(dir)
        .map_err(|e| write_error(path, &e))?;
    tmp.write_all(content)
        .and_then(|_| tmp.as_file().sync_all())
        .map_err(|e| write_error(path, &e))?;
    tmp.persist(path)
        .map_err(|e| anyhow!("cannot write `{}`: {}", path.display(), e.error))?;
    Ok(())
}

/// Lets `produce` write a file at a temporary path beside `path` (same extension: encoders pick
/// the format from it), then renames it into place: `path` is either the old file or the new
/// complete one. Without a lock (see [`OutputDir`] for a command's set of files).
pub fn atomic_with(path: &Path, produce: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let tmp = builder()
        .prefix(PARTIAL_PREFIX)
        .suffix(&ext)
        .tempfile_in(dir)
        .map_err(|e| write_error(path, &e))?
        .into_temp_path();
    produce(&tmp)?;
    File::open(&tmp)
        .and_then(|f| f.sync_all())
        .map_err(|e| write_error(path, &e))?;
    tmp.persist(path)
        .map_err(|e| anyhow!("cannot write `{}`: {}", path.display(), e.error))?;
    Ok(())
}

/// How messages spell an option: `--name` for the command line (the default), `name=` for
/// the Python package ([`spell_options_for_python`]), whose keyword arguments mirror the
/// options.
static PYTHON_SPELLING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Messages name options as Python keyword arguments (`transient=`) from now on in this
/// process (the Python package calls it on import).
pub fn spell_options_for_python() {
    PYTHON_SPELLING.store(true, std::sync::atomic::Ordering::Relaxed);
}

/// The option `name` (without dashes) as messages spell it: `--name`, or `name=` in the
/// Python package.
pub fn option(name: &str) -> String {
    if PYTHON_SPELLING.load(std::sync::atomic::Ordering::Relaxed) {
        format!("{}=", name.replace('-', "_"))
    } else {
        format!("--{name}")
    }
}
