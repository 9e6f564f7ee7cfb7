//! `pipeline.toml`: the parser (`core::config::PipelineFile::parse` with the registered stage
//! sections) and every stage's validation (`stages::build`), as `hdi run` loads a file.
use hdi::core::config::PipelineFile;

fn main() {
    let kinds = hdi::stages::section_names();
    afl::fuzz_nohook!(|data: &[u8]| {
        // A pipeline file is read with `read_to_string`: non-UTF-8 bytes never reach the parser.
        let Ok(text) = std::str::from_utf8(data) else {
            return;
        };
        // Relative input paths resolve against the scratch directory, which holds no inputs.
        let path = hdi_fuzz::scratch_dir().join("pipeline.toml");
        if let Ok(file) = PipelineFile::parse(&path, text.to_string(), &kinds) {
            let _ = hdi::stages::build(&file);
        }
    });
}
