//! The `transform` target: the checks of `checks/transform.rs` on each input (docs/reliability.md).

#![no_main]

mod common;
#[path = "checks/transform.rs"]
mod check;

libfuzzer_sys::fuzz_target!(|data: &[u8]| check::run(data));
