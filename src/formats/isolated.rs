//! Running a reader in a child process, so that a crash inside a C library becomes an error.
//!
//! Debian's libhdf5 1.10 segfaults, aborts on an invalid `free` or spins on crafted `.h5` and
//! `.datx` files (docs/reliability.md, "Coverage-guided fuzzing"): memory-safety bugs of the C
//! library that no check in hdi's readers can catch. [`run`] forks, reads in the child and
//! sends the result back through a pipe in a small binary encoding the caller writes
//! ([`Writer`], [`Reader`]). A child killed by a signal, or still busy after the time limit, is
//! a [`ChildFailure`] the reader turns into an error naming the file; hdi's own memory never
//! sees what the library did with the hostile bytes.
//!
//! Why fork and not a helper executable: the library (and the test and fuzz binaries that link
//! it) has no executable of its own to start, and the child needs nothing but the code already
//! mapped. A fork of a threaded process may only touch what no other thread can hold locked:
//! [`read_hdf5`] takes the HDF5 bindings' global lock around [`run`] (the child inherits it,
//! held by its one thread), the readers use neither rayon nor logging, and glibc's `malloc` is
//! fork-safe. The child's stdout and stderr go to `/dev/null` (glibc's abort message, libhdf5's
//! diagnostics), and it leaves with `_exit`, running no destructor or `atexit` handler.
//!
//! On other than Unix the work runs in-process, as before.
use std::fmt;
use std::io::{self, Read, Write};
use std::path::Path;
use std::time::Duration;

/// Why the child gave no result.
#[derive(Debug)]
pub enum ChildFailure {
    /// Killed by a signal (SIGSEGV, SIGABRT …): the library crashed on the file.
    Crashed { signal: i32 },
    /// Still working after the time limit; killed.
    TimedOut { limit: Duration },
    /// Exited with a non-zero status (a panic the reader did not catch, a failed write).
    Exited { code: i32 },
    /// The child could not be started (pipe or fork failed) or its reply was malformed.
    System(String),
}

impl fmt::Display for ChildFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ChildFailure::Crashed { signal } => {
                write!(f, "the reader crashed ({})", signal_name(*signal))
            }
            ChildFailure::TimedOut { limit } => {
                write!(
                    f,
                    "the reader was still busy after {:.1} s",
                    limit.as_secs_f64()
                )
            }
            ChildFailure::Exited { code } => write!(f, "the reader exited with status {code}"),
            ChildFailure::System(m) => write!(f, "the reader's child process failed: {m}"),
        }
    }
}

fn signal_name(signal: i32) -> String {
    let name = match signal {
        libc::SIGSEGV => "SIGSEGV, a segmentation fault",
        libc::SIGABRT => "SIGABRT, an abort",
        libc::SIGBUS => "SIGBUS, a bus error",
        libc::SIGFPE => "SIGFPE, an arithmetic fault",
        libc::SIGILL => "SIGILL, an illegal instruction",
        libc::SIGKILL => "SIGKILL",
        _ => return format!("signal {signal}"),
    };
    name.to_string()
}

/// The time limit for reading a file of `bytes` bytes: one minute plus 1 s per 5 MB, far
/// above any honest read (HDF5 reads at ≥ 100 MB/s here, compressed data included) and short
/// enough that a spinning library does not hang a run. [`set_time_limit`] overrides it.
pub fn time_limit_for(bytes: u64) -> Duration {
    if let Some(limit) = *LIMIT_OVERRIDE.lock().unwrap_or_else(|p| p.into_inner()) {
        return limit;
    }
    Duration::from_secs(60) + Duration::from_secs_f64(bytes as f64 / 5e6)
}

static LIMIT_OVERRIDE: std::sync::Mutex<Option<Duration>> = std::sync::Mutex::new(None);

/// Replaces [`time_limit_for`]'s limit for every later read of this process (`None`: back to
/// the size rule). The fuzz targets set a short one, below AFL's hang threshold.
pub fn set_time_limit(limit: Option<Duration>) {
    *LIMIT_OVERRIDE.lock().unwrap_or_else(|p| p.into_inner()) = limit;
}

/// Little-endian encoding of the child's reply.
pub struct Writer<'a> {
    out: &'a mut dyn Write,
}

impl Writer<'_> {
    pub fn u64(&mut self, x: u64) -> io::Result<()> {
        self.out.write_all(&x.to_le_bytes())
    }
    pub fn f64(&mut self, x: f64) -> io::Result<()> {
        self.out.write_all(&x.to_bits().to_le_bytes())
    }
    pub fn bool(&mut self, x: bool) -> io::Result<()> {
        self.out.write_all(&[x as u8])
    }
    pub fn str(&mut self, s: &str) -> io::Result<()> {
        self.u64(s.len() as u64)?;
        self.out.write_all(s.as_bytes())
    }
    pub fn opt_f64(&mut self, x: Option<f64>) -> io::Result<()> {
        self.bool(x.is_some())?;
        self.f64(x.unwrap_or(0.0))
    }
    /// A length, then the values in blocks (no copy of the whole slice).
    pub fn f64s(&mut self, v: &[f64]) -> io::Result<()> {
        self.u64(v.len() as u64)?;
        let mut block = [0u8; 8 * 1024];
        for chunk in v.chunks(1024) {
            for (b, x) in block.chunks_exact_mut(8).zip(chunk) {
                b.copy_from_slice(&x.to_bits().to_le_bytes());
            }
            self.out.write_all(&block[..8 * chunk.len()])?;
        }
        Ok(())
    }
}

/// Decoding of [`Writer`]'s encoding. Memory grows with the bytes that arrive, never with a
/// stated length alone, so a garbled reply cannot ask for a huge allocation.
pub struct Reader<'a> {
    input: &'a mut dyn Read,
}

impl Reader<'_> {
    fn bad(what: &str) -> io::Error {
        io::Error::new(io::ErrorKind::InvalidData, what.to_string())
    }
    pub fn u64(&mut self) -> io::Result<u64> {
        let mut b = [0u8; 8];
        self.input.read_exact(&mut b)?;
        Ok(u64::from_le_bytes(b))
    }
    pub fn f64(&mut self) -> io::Result<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    pub fn bool(&mut self) -> io::Result<bool> {
        let mut b = [0u8; 1];
        self.input.read_exact(&mut b)?;
        match b[0] {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(Self::bad("not a boolean")),
        }
    }
    /// A length or count, as `usize`.
    pub fn usize(&mut self) -> io::Result<usize> {
        usize::try_from(self.u64()?).map_err(|_| Self::bad("length beyond usize"))
    }
    pub fn str(&mut self) -> io::Result<String> {
        let n = self.u64()?;
        let mut b = Vec::new();
        (&mut self.input).take(n).read_to_end(&mut b)?;
        if b.len() as u64 != n {
            return Err(io::ErrorKind::UnexpectedEof.into());
        }
        String::from_utf8(b).map_err(|_| Self::bad("not UTF-8"))
    }
    pub fn opt_f64(&mut self) -> io::Result<Option<f64>> {
        let some = self.bool()?;
        let x = self.f64()?;
        Ok(some.then_some(x))
    }
    pub fn f64s(&mut self) -> io::Result<Vec<f64>> {
        let n = self.usize()?;
        let mut v = Vec::with_capacity(n.min(1 << 20));
        let mut block = [0u8; 8 * 1024];
        while v.len() < n {
            let k = (n - v.len()).min(1024);
            self.input.read_exact(&mut block[..8 * k])?;
            v.extend(
                block[..8 * k].chunks_exact(8).map(|b| {
                    f64::from_bits(u64::from_le_bytes(b.try_into().expect("8-byte chunk")))
                }),
            );
        }
        Ok(v)
    }
}

/// [`run`] for a reader of the HDF5 file at `path`, with [`time_limit_for`] its size. The HDF5
/// bindings' global lock is held across the fork, so no other thread is inside libhdf5 when
/// the child copies its state (the child's reads re-enter the lock it inherits).
pub fn read_hdf5<T>(
    path: &Path,
    work: impl FnOnce() -> T,
    send: impl FnOnce(T, &mut Writer) -> io::Result<()>,
    receive: impl FnOnce(&mut Reader) -> io::Result<T>,
) -> Result<T, ChildFailure> {
    let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    hdf5::sync::sync(|| run(time_limit_for(bytes), work, send, receive))
}

/// Runs `work` in a child process and returns what `receive` decodes from what `send` wrote
/// there, or why there is nothing. `send` owns the value, so it can free each array once
/// written: the child's copy shrinks while the parent's grows. The caller holds whatever
/// global lock the work's library needs (module docs; [`read_hdf5`] for libhdf5).
pub fn run<T>(
    limit: Duration,
    work: impl FnOnce() -> T,
    send: impl FnOnce(T, &mut Writer) -> io::Result<()>,
    receive: impl FnOnce(&mut Reader) -> io::Result<T>,
) -> Result<T, ChildFailure> {
    #[cfg(unix)]
    {
        unix::run(limit, work, send, receive)
    }
    #[cfg(not(unix))]
    {
        let _ = (limit, send, receive);
        Ok(work())
    }
}

#[cfg(unix)]
mod unix {
    use super::{ChildFailure, Reader, Writer};
    use std::fs::File;
    use std::io::{self, BufReader, BufWriter, Read, Write};
    use std::os::fd::{AsRawFd, FromRawFd};
    use std::time::{Duration, Instant};

    fn os_error(what: &str) -> ChildFailure {
        ChildFailure::System(format!("{what}: {}", io::Error::last_os_error()))
    }

    pub(super) fn run<T>(
        limit: Duration,
        work: impl FnOnce() -> T,
        send: impl FnOnce(T, &mut Writer) -> io::Result<()>,
        receive: impl FnOnce(&mut Reader) -> io::Result<T>,
    ) -> Result<T, ChildFailure> {
        let mut fds = [0 as libc::c_int; 2];
        // SAFETY: `fds` has room for the two descriptors pipe2 writes.
        if unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) } != 0 {
            return Err(os_error("pipe"));
        }
        let [read_fd, write_fd] = fds;
        // A 1 MiB pipe (best effort; Linux's default is 64 KiB): fewer switches between the
        // two processes on a record of gigabytes.
        #[cfg(target_os = "linux")]
        // SAFETY: fcntl on our own open descriptor.
        unsafe {
            libc::fcntl(write_fd, libc::F_SETPIPE_SZ, 1 << 20);
        }
        // SAFETY: the child runs only the reader (module docs: no lock another thread could
        // hold) and leaves through `_exit`.
        let pid = unsafe { libc::fork() };
        if pid < 0 {
            let e = os_error("fork");
            // SAFETY: both descriptors are ours and open.
            unsafe {
                libc::close(read_fd);
                libc::close(write_fd);
            }
            return Err(e);
        }
        if pid == 0 {
            // SAFETY: in the child; the descriptors are open and owned by it.
            unsafe {
                libc::close(read_fd);
                silence_output();
                // A parent that stopped reading gives EPIPE, not a death by SIGPIPE.
                libc::signal(libc::SIGPIPE, libc::SIG_IGN);
                let mut pipe = BufWriter::with_capacity(1 << 16, File::from_raw_fd(write_fd));
                let ok = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    let value = work();
                    let mut w = Writer { out: &mut pipe };
                    send(value, &mut w).is_ok() && pipe.flush().is_ok()
                }));
                libc::_exit(match ok {
                    Ok(true) => 0,
                    Ok(false) => 1,
                    Err(_) => 101,
                });
            }
        }
        // SAFETY: the parent's copy of the write end is not used; the read end is ours.
        unsafe { libc::close(write_fd) };
        let pipe = unsafe { File::from_raw_fd(read_fd) };
        let mut input = BufReader::with_capacity(
            1 << 16,
            Deadline {
                file: pipe,
                until: Instant::now() + limit,
            },
        );
        let reply = receive(&mut Reader { input: &mut input });
        let timed_out = matches!(&reply, Err(e) if e.kind() == io::ErrorKind::TimedOut);
        if timed_out {
            // SAFETY: `pid` is our child, not yet reaped.
            unsafe { libc::kill(pid, libc::SIGKILL) };
        }
        drop(input);
        let status = wait(pid)?;
        if timed_out {
            return Err(ChildFailure::TimedOut { limit });
        }
        if libc::WIFSIGNALED(status) {
            return Err(ChildFailure::Crashed {
                signal: libc::WTERMSIG(status),
            });
        }
        let code = if libc::WIFEXITED(status) {
            libc::WEXITSTATUS(status)
        } else {
            -1
        };
        match (code, reply) {
            (0, Ok(value)) => Ok(value),
            // A reply that decodes wrongly is ours to report, whatever the child did after.
            (_, Err(e)) if code == 0 || e.kind() == io::ErrorKind::InvalidData => {
                Err(ChildFailure::System(format!("malformed reply: {e}")))
            }
            (code, _) => Err(ChildFailure::Exited { code }),
        }
    }

    /// Points the child's stdout and stderr at /dev/null: hdi's stdout may be JSON, and a
    /// crashing library's last words are reported as the error instead.
    unsafe fn silence_output() {
        let null = libc::open(c"/dev/null".as_ptr(), libc::O_WRONLY);
        if null >= 0 {
            libc::dup2(null, 1);
            libc::dup2(null, 2);
            libc::close(null);
        }
    }

    fn wait(pid: libc::pid_t) -> Result<libc::c_int, ChildFailure> {
        let mut status = 0;
        loop {
            // SAFETY: `pid` is our child; `status` is a valid out-parameter.
            let r = unsafe { libc::waitpid(pid, &mut status, 0) };
            if r == pid {
                return Ok(status);
            }
            if io::Error::last_os_error().kind() != io::ErrorKind::Interrupted {
                return Err(os_error("waitpid"));
            }
        }
    }

    /// The pipe's read end with a deadline: each read first polls until the time left.
    struct Deadline {
        file: File,
        until: Instant,
    }

    impl Read for Deadline {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            loop {
                let left = self.until.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    return Err(io::ErrorKind::TimedOut.into());
                }
                let mut p = libc::pollfd {
                    fd: self.file.as_raw_fd(),
                    events: libc::POLLIN,
                    revents: 0,
                };
                let ms = left.as_millis().clamp(1, i32::MAX as u128) as libc::c_int;
                // SAFETY: one valid pollfd.
                match unsafe { libc::poll(&mut p, 1, ms) } {
                    0 => continue,
                    r if r > 0 => return self.file.read(buf),
                    _ => {
                        let e = io::Error::last_os_error();
                        if e.kind() != io::ErrorKind::Interrupted {
                            return Err(e);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    fn send_vec(v: Vec<f64>, w: &mut Writer) -> io::Result<()> {
        w.f64s(&v)
    }
    fn receive_vec(r: &mut Reader) -> io::Result<Vec<f64>> {
        r.f64s()
    }

    #[test]
    fn a_result_comes_back_bit_for_bit() {
        let v: Vec<f64> = (0..5000)
            .map(|i| (i as f64 * 0.37).sin() / 3.0)
            .chain([f64::NAN, -0.0, f64::INFINITY, f64::MIN_POSITIVE / 2.0])
            .collect();
        let expected = v.clone();
        let got = run(Duration::from_secs(30), move || v, send_vec, receive_vec).unwrap();
        assert_eq!(got.len(), expected.len());
        assert!(got
            .iter()
            .zip(&expected)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn strings_and_options_round_trip() {
        let got = run(
            Duration::from_secs(30),
            || ("µm — Zygo".to_string(), Some(2.5), None::<f64>, true),
            |t: (String, Option<f64>, Option<f64>, bool), w| {
                w.str(&t.0)?;
                w.opt_f64(t.1)?;
                w.opt_f64(t.2)?;
                w.bool(t.3)
            },
            |r| Ok((r.str()?, r.opt_f64()?, r.opt_f64()?, r.bool()?)),
        )
        .unwrap();
        assert_eq!(got, ("µm — Zygo".to_string(), Some(2.5), None, true));
    }

    #[test]
    fn a_segfault_in_the_child_is_an_error_naming_the_signal() {
        let e = run(
            Duration::from_secs(30),
            || {
                // SAFETY: the child is meant to die here. Rust's own SIGSEGV handler (stack
                // overflow detection) would return from a raised signal, so it goes first.
                unsafe {
                    libc::signal(libc::SIGSEGV, libc::SIG_DFL);
                    libc::raise(libc::SIGSEGV);
                }
                Vec::new()
            },
            send_vec,
            receive_vec,
        )
        .unwrap_err();
        assert!(
            matches!(e, ChildFailure::Crashed { signal } if signal == libc::SIGSEGV),
            "{e:?}"
        );
        assert!(e.to_string().contains("SIGSEGV"), "{e}");
    }

    #[test]
    fn an_abort_in_the_child_is_an_error() {
        let e = run(
            Duration::from_secs(30),
            || -> Vec<f64> { std::process::abort() },
            send_vec,
            receive_vec,
        )
        .unwrap_err();
        assert!(
            matches!(e, ChildFailure::Crashed { signal } if signal == libc::SIGABRT),
            "{e:?}"
        );
    }

    #[test]
    fn a_child_that_spins_is_killed_at_the_limit() {
        let started = std::time::Instant::now();
        let e = run(
            Duration::from_millis(300),
            || -> Vec<f64> {
                loop {
                    std::thread::sleep(Duration::from_millis(50));
                }
            },
            send_vec,
            receive_vec,
        )
        .unwrap_err();
        assert!(matches!(e, ChildFailure::TimedOut { .. }), "{e:?}");
        assert!(started.elapsed() < Duration::from_secs(20));
    }

    #[test]
    fn a_panic_in_the_child_is_an_exit_status() {
        let e = run(
            Duration::from_secs(30),
            || -> Vec<f64> { panic!("reader bug") },
            send_vec,
            receive_vec,
        )
        .unwrap_err();
        assert!(matches!(e, ChildFailure::Exited { code: 101 }), "{e:?}");
    }

    #[test]
    fn a_garbled_reply_is_refused_without_allocating_what_it_states() {
        let e = run(
            Duration::from_secs(30),
            || (),
            |_, w| w.u64(u64::MAX / 16),
            |r| r.f64s().map(|_| ()),
        )
        .unwrap_err();
        assert!(matches!(e, ChildFailure::System(_)), "{e:?}");
    }
}
