//! An external planner (`docs/planner-protocol.md`): at each replanning time the map is written as files a
//! planner reads ([`oeg::planner_files`]), the command runs with the start, the goal and the file names, and
//! the path comes back as a CSV of x and y in metres, world frame. A planner that fails in any way (it cannot
//! start, exits non-zero, runs over its time-out, writes a malformed path) gives a [`PlannerFailure`] that
//! names the file and the line, and the run goes on.

use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::error::Result;
use crate::output::write_bytes;

/// The largest path file read back, bytes.
pub const MAX_PATH_FILE_BYTES: u64 = 16 << 20;
/// The stderr kept from a failed call, bytes (its end).
const STDERR_TAIL_BYTES: usize = 2000;

/// An external planner: its command line, its time-out, and the folder the map and the path are exchanged
/// in.
#[derive(Debug, Clone, PartialEq)]
pub struct ExternalPlanner {
    /// Program, then its own arguments; the protocol's seven arguments follow them.
    pub command: Vec<String>,
    /// Wall-time limit of one call.
    pub timeout: Duration,
    /// Where `map.pgm`, `map.yaml`, the `.npy` layers, `layers.json` and `path.csv` are exchanged.
    pub dir: PathBuf,
    /// Where that folder is once the run's output is in place (`OUT/planner`): messages name the files there,
    /// never in the staging folder that is gone by the time they are read.
    pub shown_dir: PathBuf,
}

/// Why a call gave no path.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannerFailure {
    /// `timeout`, `exit`, `spawn` or `malformed_path`.
    pub kind: &'static str,
    /// What happened, naming the file and the line where there is one.
    pub message: String,
}

/// The region's extent a path must stay in: min x, max x, min y, max y, metres.
pub type Extent = [f64; 4];

/// The extent of `window`'s cells.
pub fn extent_of(window: &oeg::GridWindow) -> Extent {
    let ((x0, y0), (w, h)) = (window.min_corner_m(), window.size_m());
    [x0, x0 + w, y0, y0 + h]
}

impl ExternalPlanner {
    /// Writes `files` (the map) into the exchange folder, runs the command with
    /// `START_X START_Y GOAL_X GOAL_Y MAP_YAML LAYERS_JSON PATH_CSV` after its own arguments, and reads the
    /// path back. `Ok(Err(..))` is the planner's failure, an event of the run; `Err` is the testbed's own
    /// failure to write the files.
    ///
    /// # Errors
    /// A map file that cannot be written.
    pub fn call(
        &self,
        files: &[(String, Vec<u8>)],
        start: (f64, f64),
        goal: (f64, f64),
        extent: Extent,
    ) -> Result<std::result::Result<Vec<(f64, f64)>, PlannerFailure>> {
        for (name, bytes) in files {
            write_bytes(&self.dir.join(name), bytes)?;
        }
        let path_csv = self.dir.join("path.csv");
        // A path left from the last call must not pass for this call's.
        if path_csv.exists() {
            let _ = std::fs::remove_file(&path_csv);
        }
        let shown = self.shown_dir.join("path.csv");
        Ok(self.run(start, goal, &path_csv).and_then(|()| {
            let bytes = read_regular(&path_csv, MAX_PATH_FILE_BYTES).map_err(|e| PlannerFailure {
                kind: "malformed_path",
                message: format!("{}: no readable path: {e}", shown.display()),
            })?;
            parse_path(&shown, &bytes, extent)
        }))
    }

    fn run(
        &self,
        start: (f64, f64),
        goal: (f64, f64),
        path_csv: &Path,
    ) -> std::result::Result<(), PlannerFailure> {
        use std::os::unix::process::CommandExt as _;
        let program = self.command.first().map_or("", String::as_str);
        let number = |v: f64| format!("{v}");
        let mut child = Command::new(program)
            .args(&self.command[1..])
            .args([number(start.0), number(start.1), number(goal.0), number(goal.1)])
            .arg(self.dir.join("map.yaml"))
            .arg(self.dir.join("layers.json"))
            .arg(path_csv)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            // Its own process group, so that the call ends with every process it started.
            .process_group(0)
            .spawn()
            .map_err(|e| PlannerFailure {
                kind: "spawn",
                message: format!(
                    "the planner command {} could not start: {e}",
                    shown_command(&self.command)
                ),
            })?;
        // stderr is drained on its own thread into a bounded tail, so a chatty planner never blocks on a full
        // pipe and never fills the memory.
        let tail = Arc::new(Mutex::new(StderrTail::default()));
        let reader = child.stderr.take().map(|mut pipe| {
            let tail = Arc::clone(&tail);
            std::thread::spawn(move || {
                let mut chunk = [0u8; 4096];
                while let Ok(n @ 1..) = pipe.read(&mut chunk) {
                    if let Ok(mut t) = tail.lock() {
                        t.push(&chunk[..n]);
                    }
                }
            })
        });
        let started = Instant::now();
        let status = loop {
            match child.try_wait() {
                Ok(Some(status)) => break Some(status),
                Ok(None) if started.elapsed() >= self.timeout => break None,
                Ok(None) => std::thread::sleep(Duration::from_millis(2)),
                Err(_) => break None,
            }
        };
        // The call is over: nothing it started outlives it (a child left holding the pipe would otherwise keep
        // the run waiting).
        let group = rustix::process::Pid::from_child(&child);
        let _ = rustix::process::kill_process_group(group, rustix::process::Signal::KILL);
        let _ = child.kill();
        let _ = child.wait();
        // A process that left the group (setsid) may still hold the pipe: its tail is taken as it is, and the
        // reader ends when the pipe closes.
        if let Some(reader) = reader {
            let waited = Instant::now();
            while !reader.is_finished() && waited.elapsed() < STDERR_GRACE {
                std::thread::sleep(Duration::from_millis(1));
            }
        }
        let tail = tail.lock().map(|t| t.text()).unwrap_or_default();
        let with_stderr = |m: String| {
            if tail.is_empty() {
                m
            } else {
                format!("{m}; its stderr ends: {tail}")
            }
        };
        match status {
            None => Err(PlannerFailure {
                kind: "timeout",
                message: format!(
                    "the planner {} ran over its time-out of {} s and was stopped with every process it started",
                    shown_command(&self.command),
                    self.timeout.as_secs_f64()
                ),
            }),
            Some(s) if !s.success() => Err(PlannerFailure {
                kind: "exit",
                message: with_stderr(format!(
                    "the planner {} exited with {s}",
                    shown_command(&self.command)
                )),
            }),
            Some(_) => Ok(()),
        }
    }
}

/// How long the end of a planner's stderr is waited for once the call is over.
const STDERR_GRACE: Duration = Duration::from_millis(200);

/// The last [`STDERR_TAIL_BYTES`] bytes a planner wrote to stderr.
#[derive(Default)]
struct StderrTail {
    bytes: std::collections::VecDeque<u8>,
}

impl StderrTail {
    fn push(&mut self, chunk: &[u8]) {
        self.bytes.extend(chunk);
        let over = self.bytes.len().saturating_sub(STDERR_TAIL_BYTES);
        self.bytes.drain(..over);
    }

    /// The tail as text, trimmed, starting at a whole character.
    fn text(&self) -> String {
        let bytes: Vec<u8> = self.bytes.iter().copied().collect();
        let text = String::from_utf8_lossy(&bytes);
        text.trim().trim_start_matches('\u{fffd}').to_string()
    }
}

/// A command as it will run: its exact argument vector, quoted, with every control and non-printing character
/// escaped (`["sh", "-c", "a; b"]`, `"\u{1b}[2K"`), so that what a message shows is what runs.
pub fn shown_command(command: &[String]) -> String {
    format!("{command:?}")
}

/// Reads a path file: one point per line, `x,y` in metres (world frame), an optional header line
/// (`x_m,y_m` or `x,y`) and `#` comments. Every point must be finite and inside `extent`.
///
/// # Errors
/// A [`PlannerFailure`] of kind `malformed_path` naming the file and the line.
pub fn read_path(path: &Path, extent: Extent) -> std::result::Result<Vec<(f64, f64)>, PlannerFailure> {
    let fail = |message: String| PlannerFailure {
        kind: "malformed_path",
        message,
    };
    let bytes = read_regular(path, MAX_PATH_FILE_BYTES)
        .map_err(|e| fail(format!("{}: no readable path: {e}", path.display())))?;
    parse_path(path, &bytes, extent)
}

/// A path file's points from its bytes (`path` names it in errors), as [`read_path`] reads them.
///
/// # Errors
/// As [`read_path`].
pub fn parse_path(
    path: &Path,
    bytes: &[u8],
    extent: Extent,
) -> std::result::Result<Vec<(f64, f64)>, PlannerFailure> {
    let fail = |message: String| PlannerFailure {
        kind: "malformed_path",
        message,
    };
    let name = path.display();
    let text = std::str::from_utf8(bytes).map_err(|e| {
        fail(format!(
            "{name}: byte {}: not UTF-8 text; expected lines of x,y",
            e.valid_up_to()
        ))
    })?;
    let mut points = Vec::new();
    let mut header_allowed = true;
    for (k, line) in text.lines().enumerate() {
        let at = k + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if std::mem::take(&mut header_allowed)
            && fields.len() == 2
            && fields
                .iter()
                .all(|f| f.starts_with(|c: char| c.is_ascii_alphabetic()) && !is_number(f))
        {
            continue;
        }
        let [x, y] = fields[..] else {
            return Err(fail(format!(
                "{name}:{at}: expected two numbers `x,y` in metres, got {} field(s): `{line}`",
                fields.len()
            )));
        };
        let parse = |v: &str, axis: &str| {
            v.parse::<f64>().map_err(|_| {
                fail(format!(
                    "{name}:{at}: {axis} `{v}` is not a number; expected metres"
                ))
            })
        };
        let (x, y) = (parse(x, "x")?, parse(y, "y")?);
        if let Some(problem) = point_problem((x, y), extent) {
            return Err(fail(format!("{name}:{at}: {problem}")));
        }
        points.push((x, y));
    }
    if points.is_empty() {
        return Err(fail(format!(
            "{name}: the path is empty; expected at least one line x,y"
        )));
    }
    Ok(points)
}

/// Reads a whole regular file of at most `limit` bytes. The file is opened without blocking and refused unless
/// it is a regular file, so a FIFO, a device or a socket put in the file's place never holds the run.
fn read_regular(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    use rustix::fs::{Mode, OFlags};
    let fd = rustix::fs::open(
        path,
        OFlags::RDONLY | OFlags::NONBLOCK | OFlags::CLOEXEC,
        Mode::empty(),
    )?;
    let file = std::fs::File::from(fd);
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(std::io::Error::other(format!(
            "is a {}, not a regular file",
            file_kind(&meta.file_type())
        )));
    }
    if meta.len() > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!("is {} bytes, over the limit of {limit} bytes", meta.len()),
        ));
    }
    let mut bytes = Vec::new();
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!("grew past the limit of {limit} bytes while read"),
        ));
    }
    Ok(bytes)
}

/// What kind of file a non-regular file is, in words.
fn file_kind(t: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt as _;
    if t.is_dir() {
        "folder"
    } else if t.is_fifo() {
        "FIFO"
    } else if t.is_socket() {
        "socket"
    } else if t.is_char_device() || t.is_block_device() {
        "device"
    } else {
        "special file"
    }
}

/// What is wrong with a path's point: not finite, or off the map's `extent`; `None` for a good point.
pub fn point_problem((x, y): (f64, f64), extent: Extent) -> Option<String> {
    let [x0, x1, y0, y1] = extent;
    if !(x.is_finite() && y.is_finite()) {
        return Some(format!("({x}, {y}) is not a finite point"));
    }
    if !(x0..=x1).contains(&x) || !(y0..=y1).contains(&y) {
        return Some(format!(
            "({x}, {y}) m lies off the map, which spans x {x0} .. {x1} m and y {y0} .. {y1} m"
        ));
    }
    None
}

fn is_number(v: &str) -> bool {
    v.parse::<f64>().is_ok()
}

/// Splits a command line given as one string into words: spaces separate, single or double quotes keep
/// spaces in a word, a backslash outside single quotes keeps the next character. No variables, no globs: the
/// words go to the program as they are.
///
/// # Errors
/// An unclosed quote or an empty command, as a message.
pub fn split_command(line: &str) -> std::result::Result<Vec<String>, String> {
    let (mut words, mut word, mut in_word) = (Vec::new(), String::new(), false);
    let mut chars = line.chars();
    let mut quote: Option<char> = None;
    while let Some(c) = chars.next() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some('\''), c) => word.push(c),
            (_, '\\') => {
                if let Some(next) = chars.next() {
                    word.push(next);
                    in_word = true;
                }
            }
            (Some(_), c) => word.push(c),
            (None, '\'' | '"') => {
                quote = Some(c);
                in_word = true;
            }
            (None, c) if c.is_whitespace() => {
                if in_word {
                    words.push(std::mem::take(&mut word));
                    in_word = false;
                }
            }
            (None, c) => {
                word.push(c);
                in_word = true;
            }
        }
    }
    if let Some(q) = quote {
        return Err(format!("the command `{line}` has an unclosed {q}"));
    }
    if in_word {
        words.push(word);
    }
    if words.is_empty() {
        return Err("the planner command is empty".into());
    }
    Ok(words)
}

#[cfg(test)]
#[allow(clippy::disallowed_methods, reason = "tests write their inputs directly")]
mod tests {
    use super::*;

    const EXTENT: Extent = [-1.0, 10.0, -5.0, 5.0];

    fn path_from(text: &str) -> std::result::Result<Vec<(f64, f64)>, PlannerFailure> {
        let dir = std::env::temp_dir().join(format!("oeg-path-{}-{}", std::process::id(), text.len()));
        std::fs::create_dir_all(&dir).expect("dir");
        let p = dir.join("path.csv");
        std::fs::write(&p, text).expect("write");
        read_path(&p, EXTENT)
    }

    #[test]
    fn a_path_reads_with_or_without_a_header() {
        assert_eq!(
            path_from("x_m,y_m\n0,0\n1.5, 2\n").expect("path"),
            [(0.0, 0.0), (1.5, 2.0)]
        );
        assert_eq!(
            path_from("# comment\n0,0\n\n3,4\n").expect("path"),
            [(0.0, 0.0), (3.0, 4.0)]
        );
    }

    #[test]
    fn each_malformed_path_names_the_file_and_the_line() {
        for (text, expected) in [
            ("x,y\n0,0\nzero,1\n", "path.csv:3: x `zero` is not a number"),
            ("0,0\nNaN,1\n", "path.csv:2: (NaN, 1) is not a finite point"),
            ("0,0\n1,2,3\n", "path.csv:2: expected two numbers"),
            ("0,0\n50,0\n", "path.csv:2: (50, 0) m lies off the map"),
            ("x,y\n", "the path is empty"),
            ("", "the path is empty"),
        ] {
            let e = path_from(text).expect_err(text);
            assert_eq!(e.kind, "malformed_path");
            assert!(e.message.contains(expected), "{text:?}: {}", e.message);
        }
    }

    #[test]
    fn command_lines_split_like_a_shell_without_its_surprises() {
        assert_eq!(
            split_command("python3 plan.py").expect("ok"),
            ["python3", "plan.py"]
        );
        assert_eq!(
            split_command(r#"sh -c 'echo $HOME' "a b" c\ d"#).expect("ok"),
            ["sh", "-c", "echo $HOME", "a b", "c d"]
        );
        assert!(split_command("  ").is_err());
        assert!(
            split_command("sh 'open")
                .expect_err("unclosed")
                .contains("unclosed")
        );
    }

    /// A planner running `script` with `sh -c`, exchanging files in a fresh folder.
    fn shell_planner(name: &str, script: &str, timeout: Duration) -> ExternalPlanner {
        let dir = std::env::temp_dir().join(format!("oeg-planner-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        ExternalPlanner {
            command: vec!["sh".into(), "-c".into(), script.into(), "planner".into()],
            timeout,
            shown_dir: dir.clone(),
            dir,
        }
    }

    fn call(planner: &ExternalPlanner) -> std::result::Result<Vec<(f64, f64)>, PlannerFailure> {
        planner
            .call(&[], (0.0, 0.0), (1.0, 0.0), EXTENT)
            .expect("files written")
    }

    #[test]
    fn a_planner_s_child_holding_its_stderr_does_not_hold_the_run() {
        // The planner exits at once and leaves a child with its stderr open for a minute.
        let planner = shell_planner(
            "child",
            "sleep 60 & echo failed >&2; exit 3",
            Duration::from_secs(30),
        );
        let started = Instant::now();
        let e = call(&planner).expect_err("exit 3");
        assert!(
            started.elapsed() < Duration::from_secs(10),
            "{:?}",
            started.elapsed()
        );
        assert_eq!(e.kind, "exit");
        assert!(e.message.contains("its stderr ends: failed"), "{}", e.message);
    }

    #[test]
    fn a_planner_over_its_time_out_is_stopped_with_every_process_it_started() {
        let marker = std::env::temp_dir().join(format!("oeg-planner-{}-grandchild", std::process::id()));
        let _ = std::fs::remove_file(&marker);
        // A grandchild that would write the marker after the time-out, were it left running.
        let script = format!("(sleep 2; touch '{}') & sleep 60", marker.display());
        let planner = shell_planner("timeout", &script, Duration::from_millis(300));
        let e = call(&planner).expect_err("time-out");
        assert_eq!(e.kind, "timeout");
        assert!(e.message.contains("every process it started"), "{}", e.message);
        std::thread::sleep(Duration::from_secs(3));
        assert!(!marker.exists(), "the grandchild outlived the time-out");
    }

    #[test]
    fn a_planner_s_stderr_is_kept_as_a_bounded_tail() {
        // 64 MiB of stderr, then the last words.
        let script = "head -c 67108864 /dev/zero | tr '\\0' x >&2; echo ' the end' >&2; exit 1";
        let planner = shell_planner("stderr", script, Duration::from_secs(60));
        let e = call(&planner).expect_err("exit 1");
        assert!(
            e.message.ends_with("xx the end"),
            "{}",
            &e.message[e.message.len() - 40..]
        );
        assert!(
            e.message.len() < STDERR_TAIL_BYTES + 300,
            "{} bytes",
            e.message.len()
        );
    }

    #[test]
    fn a_fifo_as_the_path_file_is_refused_not_waited_on() {
        // The planner leaves a FIFO where its path should be; reading it would wait for a writer forever.
        let planner = shell_planner("fifo", "mkfifo \"$7\"", Duration::from_secs(30));
        let e = call(&planner).expect_err("a FIFO");
        assert_eq!(e.kind, "malformed_path");
        assert!(
            e.message.contains("is a FIFO, not a regular file"),
            "{}",
            e.message
        );
        let planner = shell_planner("dir", "mkdir \"$7\"", Duration::from_secs(30));
        let e = call(&planner).expect_err("a folder");
        assert!(e.message.contains("not a regular file"), "{}", e.message);
    }

    #[test]
    fn a_command_is_shown_as_its_exact_argument_vector_with_control_characters_escaped() {
        let command = ["sh", "-c", "a; b", "rm -rf ~\u{1b}[2K\r\u{202e}ls"].map(String::from);
        assert_eq!(
            shown_command(&command),
            r#"["sh", "-c", "a; b", "rm -rf ~\u{1b}[2K\r\u{202e}ls"]"#
        );
    }
}
