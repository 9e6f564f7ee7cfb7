//! Throughput and peak memory of every height-map and LDV reader on the files under given
//! directories (docs/performance.md, "Reader throughput"). Each file is read in a child process
//! (the command line's `hdi bench --read-one FILE`) so that its peak resident memory (Linux
//! `VmHWM`) belongs to that one read: [`read_one`] is the child's work, [`ReadTiming`] its
//! one-line answer, [`table_row`] the parent's line. Files neither family recognises are
//! skipped.

use super::{BenchError, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Whether a file's content looks like a height map / an LDV record to the readers (text
/// formats are left out: their throughput is a parser's, not a format's).
fn families(path: &Path) -> (bool, bool) {
    use std::io::Read;
    let mut head = vec![0u8; 64 * 1024];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .unwrap_or(0);
    head.truncate(n);
    let surface =
        crate::surface::io::detect_format(&head).is_some_and(|f| f != "ascii" && f != "xyz");
    let ldv = matches!(
        crate::dmw::io::detect_format(path),
        Ok(f) if f != crate::dmw::io::LdvFormat::Csv
    );
    (surface, ldv)
}

/// Whether a binary reader of either family recognises `path`.
pub fn readable(path: &Path) -> bool {
    let (surface, ldv) = families(path);
    surface || ldv
}

/// One read: the format's name and the number of values read.
fn read_once(file: &Path, surface: bool) -> Result<String> {
    if surface {
        let map = crate::surface::io::read_height_map(file, &Default::default())?;
        Ok(format!("{} {}", map.source.format, map.nx() * map.ny()))
    } else {
        let format = crate::dmw::io::detect_format(file)?.name();
        let rec = crate::dmw::io::read_ldv(file, &Default::default())?;
        Ok(format!("{format} {}", rec.velocity.len()))
    }
}

/// What the child measured: the best of three reads, its peak RSS and what it read.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadTiming {
    pub seconds: f64,
    pub peak_rss_bytes: u64,
    pub format: String,
    pub values: String,
}

impl ReadTiming {
    /// The child's output line, `seconds peak_rss_bytes format values`.
    pub fn child_line(&self) -> String {
        format!(
            "{} {} {} {}",
            self.seconds, self.peak_rss_bytes, self.format, self.values
        )
    }

    /// The child's line read back (`None` if it is not one).
    pub fn parse_child_line(text: &str) -> Option<Self> {
        let f: Vec<&str> = text.split_whitespace().collect();
        let [secs, rss, format, values] = f[..] else {
            return None;
        };
        Some(ReadTiming {
            seconds: secs.parse().ok()?,
            // Printed as an integer; read as a float like the parent always did.
            peak_rss_bytes: rss.parse::<f64>().ok()? as u64,
            format: format.to_string(),
            values: values.to_string(),
        })
    }
}

/// The child: read `file` three times (as a height map if that works, else as an LDV record).
pub fn read_one(file: &Path) -> Result<ReadTiming> {
    let (surface, ldv) = families(file);
    let as_surface = surface && read_once(file, true).is_ok();
    if !as_surface && !ldv {
        return Err(BenchError::Input {
            path: file.to_path_buf(),
            message: "no binary reader reads it".into(),
        });
    }
    let mut best = f64::INFINITY;
    let mut described = String::new();
    for _ in 0..3 {
        let t = Instant::now();
        described = read_once(file, as_surface)?;
        best = best.min(t.elapsed().as_secs_f64());
    }
    let (format, values) = described.split_once(' ').unwrap_or((&described, ""));
    Ok(ReadTiming {
        seconds: best,
        peak_rss_bytes: peak_rss_bytes().unwrap_or(0),
        format: format.to_string(),
        values: values.to_string(),
    })
}

/// Peak resident set size of this process (Linux), bytes.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Every file under `dirs` (recursively, sorted per directory) that a binary reader reads.
pub fn readable_files(dirs: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for d in dirs {
        files_under(d, &mut files)?;
    }
    files.retain(|f| readable(f));
    Ok(files)
}

fn files_under(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(BenchError::io("reading", dir))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files_under(&p, out)?;
        } else {
            out.push(p);
        }
    }
    Ok(())
}

/// The table's header line.
pub fn table_header() -> String {
    format!(
        "{:<48} {:>10} {:>10} {:>10} {:>11} {:>12}",
        "file", "format", "MB", "MB/s", "values", "peak RSS MB"
    )
}

/// One file's line: name, format, size, throughput, values read, peak RSS.
pub fn table_row(file: &Path, t: &ReadTiming) -> Result<String> {
    let name = file.file_name().unwrap_or_default().to_string_lossy();
    let rss = t.peak_rss_bytes as f64 / 1e6;
    let mb = std::fs::metadata(file)
        .map_err(BenchError::io("reading", file))?
        .len() as f64
        / 1e6;
    Ok(format!(
        "{name:<48} {:>10} {mb:>10.3} {:>10.1} {:>11} {rss:>12.1}",
        t.format,
        mb / t.seconds,
        t.values
    ))
}

#[cfg(test)]
mod tests {
    use super::ReadTiming;

    #[test]
    fn the_child_line_reads_back() {
        let t = ReadTiming {
            seconds: 0.125,
            peak_rss_bytes: 4096,
            format: "gwy".into(),
            values: "1024".into(),
        };
        assert_eq!(t.child_line(), "0.125 4096 gwy 1024");
        assert_eq!(ReadTiming::parse_child_line(&t.child_line()), Some(t));
        assert_eq!(ReadTiming::parse_child_line("0.1 2"), None);
    }
}
