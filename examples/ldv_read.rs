//! Reads one LDV record and prints its size, the read time and the throughput: the probe
//! behind docs/performance.md "LDV reader throughput" (run under `/usr/bin/time -v` for the
//! peak RSS). `cargo run --release --example ldv_read -- FILE [SAMPLE_RATE_HZ]`.

use hdi::dmw::io::{read_ldv, ReadOptions};
use std::path::PathBuf;
use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(path) = args.next().map(PathBuf::from) else {
        eprintln!("usage: ldv_read FILE [SAMPLE_RATE_HZ]");
        std::process::exit(2);
    };
    let opts = ReadOptions {
        sample_rate: args.next().and_then(|s| s.parse().ok()),
        ..Default::default()
    };
    let bytes = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
    let start = Instant::now();
    match read_ldv(&path, &opts) {
        Ok(rec) => {
            let s = start.elapsed().as_secs_f64();
            let n = rec.velocity.len();
            let channels = 1 + usize::from(rec.index.is_some());
            println!(
                "{} {}: {n} samples × {channels} channels, {:.0} MB file, {s:.2} s, {:.0} MB/s \
                 (file), {:.1} Msamples/s",
                rec.format,
                path.display(),
                bytes as f64 / 1e6,
                bytes as f64 / 1e6 / s,
                n as f64 / 1e6 / s
            );
        }
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}
