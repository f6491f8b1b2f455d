//! `transform --limit 100 --format json` holds O(bodies) plus each listed placement's inputs
//! and scores, not each placement's partition (100 partitions of a 10^6-body
//! linkage, their bookkeeping and each family's copy were over 1 GB, and the command 3.4 GB).
//! A counting allocator around the system one records the peak of live bytes
//! (the tests of this binary run one at a time: none counts another's allocations).

use crate::peak_alloc;
use mbsa::generate::{self, Variant};
use mbsa::structure::Library;
use mbsa::transform::{self, TransformOptions};

/// Live bytes above those live at the start once `f` has made its value, and the peak
/// while `write` runs on it.
fn held_by<T>(f: impl FnOnce() -> T, write: impl FnOnce(&T)) -> (usize, usize) {
    let base = peak_alloc::live();
    let value = f();
    let held = peak_alloc::live() - base;
    peak_alloc::reset_peak();
    write(&value);
    let peak = peak_alloc::peak() - base;
    drop(value);
    (held, peak)
}

/// A planar Assur II linkage of 20,002 bodies, `--limit 100`, written as JSON (over 10 MB):
/// the ranked listing the command line writes ([`transform::ranked`], each partition made
/// as it is written) holds less than 300 bytes a body once the search is done (about 200:
/// the search's problem), and less than 400 while it writes; holding every listed partition
/// ([`transform::transform`], the path the command line took before: about 900 bytes a
/// body, growing with the limit) is more than twice that. The same bytes either way.
#[test]
fn limit_100_json_does_not_hold_every_partition() {
    let _serial = crate::serial();
    let m = generate::assur(2, 5_000, 364, Variant::A).unwrap();
    let lib = Library::builtin();
    let o = TransformOptions {
        limit: Some(100),
        ..TransformOptions::default()
    };
    let write = |v: &dyn erased::Json| {
        let mut len = Counter(0);
        v.write(&mut len);
        assert!(len.0 > 10_000_000, "{} bytes", len.0);
    };
    let (ranked, ranked_peak) = held_by(
        || transform::ranked(&m, &o, &lib, None).unwrap(),
        |r| write(r),
    );
    let (whole, _) = held_by(
        || transform::transform(&m, &o, &lib, None).unwrap(),
        |t| write(t),
    );
    let bodies = m.bodies.len();
    assert!(
        ranked < 300 * bodies && ranked_peak < 400 * bodies && 2 * ranked_peak < whole,
        "{ranked} bytes held ranked ({ranked_peak} writing), {whole} holding every \
         partition ({bodies} bodies)"
    );
    // The same bytes either way.
    let streamed = serde_json::to_vec_pretty(&transform::ranked(&m, &o, &lib, None).unwrap());
    let held = serde_json::to_vec_pretty(&transform::transform(&m, &o, &lib, None).unwrap());
    assert!(streamed.unwrap() == held.unwrap());
}

/// Either result, written as pretty JSON.
mod erased {
    pub trait Json {
        fn write(&self, w: &mut super::Counter);
    }
    impl<T: serde::Serialize> Json for T {
        fn write(&self, w: &mut super::Counter) {
            serde_json::to_writer_pretty(w, self).unwrap();
        }
    }
}

/// A writer that only counts bytes.
struct Counter(usize);

impl std::io::Write for Counter {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0 += b.len();
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// One S joint shared by 40,000 bodies: its 64 binary expansions are all determined (a chain
/// of balls on one centre drags what hangs beyond it), each placement listing 40,000 inputs
/// (about 7 MB). The ranked listing keeps at most 256 MiB of them, best first, where a count
/// of placements alone (at least 1,000, or `--limit`) kept them all: 1.4 GB at 10^5 bodies.
#[test]
fn a_listing_of_large_placements_is_bounded_in_bytes() {
    let _serial = crate::serial();
    let m = generate::star(40_000, mbsa::joint::JointType::S, false, true, false).unwrap();
    let lib = Library::builtin();
    let o = TransformOptions {
        limit: Some(100),
        ..TransformOptions::default()
    };
    let counts = std::cell::Cell::new((0u128, 0usize));
    let (ranked, _) = held_by(
        || transform::ranked(&m, &o, &lib, None).unwrap(),
        |r| counts.set((r.summary.determined, r.summary.listed)),
    );
    let (determined, listed) = counts.get();
    assert_eq!(determined, 64);
    assert!(
        0 < listed && (listed as u128) < determined,
        "{listed} of {determined} listed"
    );
    assert!(
        ranked < (256 << 20) + 2_000 * m.bodies.len(),
        "{ranked} bytes held for {listed} placements"
    );
}
