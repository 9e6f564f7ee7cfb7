//! One integration-test binary (one link step on 2 cores), one module per concern.
mod common;
mod pipeline_cache;
mod bad_input;
mod surface_cli;
