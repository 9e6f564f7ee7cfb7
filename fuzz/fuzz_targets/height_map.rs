//! Every height-map format through the one dispatch entry point, `surface::io::read_height_map`
//! (detection by content, then the format's reader and the common checks).
use hdi::surface::io::{read_height_map, ReadOptions};

fn main() {
    // The fallbacks a user may give for formats that do not carry sizes or units (plain ASCII,
    // GSF without ZUnits), so those readers get past their first checks.
    let opts = ReadOptions {
        channel: None,
        size_x: Some(1e-5),
        size_y: Some(1e-5),
        z_unit: Some("nm".into()),
    };
    hdi_fuzz::setup();
    afl::fuzz_nohook!(|data: &[u8]| {
        if hdi_fuzz::skip(data) {
            return;
        }
        let path = hdi_fuzz::input_file("map", data);
        let _ = read_height_map(&path, &opts);
    });
}
