//! The `load` target: the checks of `checks/load.rs` on each input (docs/reliability.md).

#![no_main]

#[path = "checks/load.rs"]
mod check;

libfuzzer_sys::fuzz_target!(|data: &[u8]| check::run(data));
