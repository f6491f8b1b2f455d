//! `mbsa analyze` writes its table as it renders it (at 10^6 bodies the table is
//! 280 MB, and held whole with its rows of cells it was the peak of `analyze --count-only`).
//! A counting allocator around the system one measures the bytes live at once
//! (the tests of this binary run one at a time: none counts another's allocations).

use crate::digest::Digest;
use crate::peak_alloc;

/// The table of a 20,000-body random spatial mechanism (count only: 13,000 groups, 5 MB of
/// text) is written with under 1 MB live beyond the analysis, and is byte for byte the table
/// `table` returns. Rendered whole, with its rows of cells, it held about 10 MB.
#[test]
fn the_table_streams_in_bounded_memory() {
    let _serial = crate::serial();
    let (m, _) = mbsa::generate::random(20_000, false, 1).expect("a random mechanism");
    let opts = mbsa::structure::Options {
        count_only: true,
        ..Default::default()
    };
    let lib = mbsa::structure::Library::builtin();
    let a = mbsa::structure::analyze(&m, &opts, &lib).expect("analysis");
    assert!(a.groups.len() > 10_000, "{} groups", a.groups.len());

    let base = peak_alloc::reset_peak();
    let mut streamed = Digest::default();
    mbsa::report::structure::write_table(&mut streamed, &a).expect("written");
    let held = peak_alloc::peak() - base;

    let whole = mbsa::report::structure::table(&a);
    let mut want = Digest::default();
    std::io::Write::write_all(&mut want, whole.as_bytes()).expect("digested");
    assert_eq!((streamed.len, streamed.hash), (want.len, want.hash));
    assert!(whole.len() > 4 << 20, "{} bytes of table", whole.len());
    assert!(
        held < 1 << 20,
        "{held} bytes held to write {} bytes of table",
        whole.len()
    );
}
