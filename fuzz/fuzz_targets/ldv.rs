//! LDV records: `dmw::io::read_ldv` (every format, detected by content) and the table-series
//! reader `hdi analyze` uses (`dmw::io::series::read_table_series`), on the same bytes.
use hdi::dmw::io::series::{read_table_series, SeriesRequest};
use hdi::dmw::io::{read_ldv, ReadOptions};

fn main() {
    let with_rate = ReadOptions {
        sample_rate: Some(1e5),
        ..ReadOptions::default()
    };
    hdi_fuzz::setup();
    afl::fuzz_nohook!(|data: &[u8]| {
        if hdi_fuzz::skip(data) {
            return;
        }
        let path = hdi_fuzz::input_file("record", data);
        // Records that state no sample rate stop at the first check without one; a second
        // read with the option covers their data paths.
        if read_ldv(&path, &ReadOptions::default()).is_err() {
            let _ = read_ldv(&path, &with_rate);
        }
        let _ = read_table_series(&path, &SeriesRequest::default());
    });
}
