//! The `rigid` target: the checks of `checks/rigid.rs` on each input (docs/reliability.md).

#![no_main]

mod common;
#[path = "checks/rigid.rs"]
mod check;

libfuzzer_sys::fuzz_target!(|data: &[u8]| check::run(data));
