//! The `analyze` target: the checks of `checks/analyze.rs` on each input (docs/reliability.md).

#![no_main]

mod common;
#[path = "checks/analyze.rs"]
mod check;

libfuzzer_sys::fuzz_target!(|data: &[u8]| check::run(data));
