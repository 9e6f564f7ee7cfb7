//! Every registered height-map reader on every input, past the content sniffers: a reader
//! normally sees only files that start with its magic, so `height_map` reaches its deeper
//! paths only through the seeds of its own format. Here each input goes to each reader
//! (`surface::io::registry::READERS`), so a new reader is fuzzed as soon as it is registered,
//! from every format's seeds (the corpus is `height_map`'s, scripts/fuzz.sh).
use hdi::surface::io::registry::READERS;
use hdi::surface::io::ReadOptions;

fn main() {
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
        let hdf5 = hdi_fuzz::is_hdf5(data);
        for reader in READERS {
            // The HDF5-based reader forks a child per file: only for HDF5 inputs.
            if reader.id == "datx" && !hdf5 {
                continue;
            }
            let _ = reader.read_file(&path, &opts);
        }
    });
}
