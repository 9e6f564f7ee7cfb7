//! `hdi bench --readers DIR…`: throughput and peak memory of every height-map and LDV reader
//! on the files under the given directories (docs/performance.md, "Reader throughput").
//!
//! Each file is read in a child process (`hdi bench --read-one FILE`) so that its peak resident
//! memory (Linux `VmHWM`) belongs to that one read; the child reads the file three times and
//! prints the best time. Files neither family recognises are skipped.

use anyhow::{bail, Context, Result};
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
        hdi::surface::io::detect_format(&head).is_some_and(|f| f != "ascii" && f != "xyz");
    let ldv = matches!(
        hdi::dmw::io::detect_format(path),
        Ok(f) if f != hdi::dmw::io::LdvFormat::Csv
    );
    (surface, ldv)
}

/// One read: the format's name and the number of values read.
fn read_once(file: &Path, surface: bool) -> Result<String> {
    if surface {
        let map = hdi::surface::io::read_height_map(file, &Default::default())?;
        Ok(format!("{} {}", map.source.format, map.nx() * map.ny()))
    } else {
        let format = hdi::dmw::io::detect_format(file)?.name();
        let rec = hdi::dmw::io::read_ldv(file, &Default::default())?;
        Ok(format!("{format} {}", rec.velocity.len()))
    }
}

/// The child: read `file` three times (as a height map if that works, else as an LDV record),
/// print `seconds peak_rss_bytes format values`.
pub(super) fn read_one(file: &Path) -> Result<()> {
    let (surface, ldv) = families(file);
    let as_surface = surface && read_once(file, true).is_ok();
    if !as_surface && !ldv {
        bail!("{}: no binary reader reads it", file.display());
    }
    let mut best = f64::INFINITY;
    let mut described = String::new();
    for _ in 0..3 {
        let t = Instant::now();
        described = read_once(file, as_surface)?;
        best = best.min(t.elapsed().as_secs_f64());
    }
    println!("{best} {} {described}", peak_rss_bytes().unwrap_or(0));
    Ok(())
}

/// Peak resident set size of this process (Linux), bytes.
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

fn files_under(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
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

/// The parent: one line per readable file, largest first within each family.
pub(super) fn bench_readers(dirs: &[PathBuf]) -> Result<()> {
    let mut files = Vec::new();
    for d in dirs {
        files_under(d, &mut files)?;
    }
    let exe = std::env::current_exe()?;
    println!(
        "{:<48} {:>10} {:>10} {:>10} {:>11} {:>12}",
        "file", "format", "MB", "MB/s", "values", "peak RSS MB"
    );
    for file in files.iter().filter(|f| {
        let (s, l) = families(f);
        s || l
    }) {
        let out = std::process::Command::new(&exe)
            .args(["bench", "--read-one"])
            .arg(file)
            .output()
            .context("running hdi bench --read-one")?;
        let name = file.file_name().unwrap_or_default().to_string_lossy();
        if !out.status.success() {
            // A deliberately corrupt test file: not a throughput figure.
            continue;
        }
        let text = String::from_utf8_lossy(&out.stdout);
        let f: Vec<&str> = text.split_whitespace().collect();
        let [secs, rss, format, values] = f[..] else {
            bail!("unexpected child output `{text}`");
        };
        let secs: f64 = secs.parse()?;
        let rss: f64 = rss.parse::<f64>()? / 1e6;
        let mb = std::fs::metadata(file)?.len() as f64 / 1e6;
        println!(
            "{name:<48} {format:>10} {mb:>10.3} {:>10.1} {values:>11} {rss:>12.1}",
            mb / secs
        );
    }
    Ok(())
}
