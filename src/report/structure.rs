//! The structural analysis as tables for people, in the layout of the paper's Table 8 (groups)
//! and Table 9 (types against the library), followed by the findings.

use crate::structure::{Analysis, Status};
use std::fmt::Write;

fn dash(s: &str) -> &str {
    if s.is_empty() { "-" } else { s }
}

/// Render the analysis.
pub fn table(a: &Analysis) -> String {
    let mut out = String::new();
    // Never flushed: the whole table stays in `out`.
    let _ = render(a, &mut out, &mut |_: &mut String| Ok(()));
    out
}

/// Bytes of rendered text held before [`write_table`] hands them to its writer.
const FLUSH_AT: usize = 1 << 16;

/// [`table`], written to `w` as it is rendered: the same bytes, without holding them. The
/// table of a 10^6-body analysis is hundreds of megabytes (280 MB for 667,261 groups), and
/// held whole with its rows it was the peak of `analyze --count-only`.
pub fn write_table<W: std::io::Write + ?Sized>(w: &mut W, a: &Analysis) -> std::io::Result<()> {
    let mut out = String::with_capacity(2 * FLUSH_AT);
    render(a, &mut out, &mut |s: &mut String| {
        if s.len() >= FLUSH_AT {
            w.write_all(s.as_bytes())?;
            s.clear();
        }
        Ok(())
    })?;
    w.write_all(out.as_bytes())
}

/// Called with the text rendered so far at row boundaries: it may write it out and clear it.
type Flush<'a> = dyn FnMut(&mut String) -> std::io::Result<()> + 'a;

fn render(a: &Analysis, out: &mut String, flush: &mut Flush<'_>) -> std::io::Result<()> {
    let status = match a.status {
        Status::Determined => "determined",
        Status::Overdetermined => "over-determined",
        Status::Underdetermined => "under-determined",
        Status::Mixed => "not determined (over- and under-determined parts)",
    };
    let groups = match a.groups.len() {
        0 => "no structural group".to_string(),
        n => format!("{n} structural group(s) on {} level(s)", a.levels),
    };
    // Where the rank check set constraint equations aside (dependent at the configuration)
    // the count is not the mobility: both, as `transform` says them ("count -2, true mobility
    // 1"). A deficit found in a group with its inputs is the inputs', not the mechanism's.
    let dependent: i64 = a
        .redundant
        .iter()
        .filter(|r| r.configuration)
        .map(|r| i64::from(r.count))
        .sum();
    let mobility = if dependent > 0 {
        format!(
            "count {}, true mobility {}",
            a.mobility.count,
            a.mobility.count + dependent
        )
    } else {
        format!("mobility {}", a.mobility.count)
    };
    let _ = writeln!(
        out,
        "{}: {groups}; {mobility}, inputs {}; {}{}",
        a.name,
        a.mobility.inputs,
        status,
        if a.count_only { " (count only)" } else { "" }
    );
    if let Some(g) = &a.geometry {
        let _ = writeln!(out, "{}", super::geometry_line(g));
    }
    if !a.groups.is_empty() {
        // The rows are made one at a time into one buffer, twice (widths, then the lines):
        // held at once, a 10^6-body analysis's 250,000 to 670,000 rows of nine cells were
        // hundreds of megabytes.
        let header = [
            "SG", "bodies", "Nm", "inputs", "level", "type", "from", "internal", "to",
        ];
        let mut rows = GroupRows {
            groups: &a.groups,
            joined: String::new(),
            widths: list_widths(&a.groups),
        };
        plain_table_with(out, &header, &mut rows, flush)?;
        out.push('\n');
        let header = [
            "SG type".to_string(),
            "SGs".to_string(),
            format!("in library ({})", a.library),
        ];
        let rows: Vec<Vec<String>> = a
            .types
            .iter()
            .map(|ty| {
                vec![
                    ty.kind.clone(),
                    ty.count.to_string(),
                    if ty.in_library { "yes" } else { "no" }.to_string(),
                ]
            })
            .collect();
        plain_table_with(out, &header, &mut SliceRows(&rows), flush)?;
        out.push('\n');
    }
    if !a.unchecked.is_empty() {
        let sizes: Vec<String> = a
            .unchecked
            .iter()
            .map(|u| format!("{} bodies ({} unknowns)", u.bodies, u.unknowns))
            .collect();
        let _ = writeln!(
            out,
            "note: the rank check left {} block(s) to the count, too large to factorize densely: {}",
            a.unchecked.len(),
            crate::structure::capped(&sizes)
        );
    }
    if !a.isolated.is_empty() {
        let list: Vec<String> = a
            .isolated
            .iter()
            .map(|i| format!("{} ({})", i.body, i.dimension))
            .collect();
        let _ = writeln!(
            out,
            "isolated freedoms (each turns one body alone, moving no other; left out): {}",
            crate::structure::capped(&list)
        );
    }
    flush(out)?;
    if let Some(d) = &a.diagnosis {
        if !d.unsolved.is_empty() {
            let _ = writeln!(
                out,
                "bodies left unsolved: {}",
                crate::structure::capped(&d.unsolved)
            );
        }
        for n in &d.notes {
            let _ = writeln!(out, "- {n}");
            flush(out)?;
        }
    } else {
        for n in &a.notes {
            let _ = writeln!(out, "- {n}");
            flush(out)?;
        }
    }
    Ok(())
}

/// The rows of a table, made on demand one at a time into a reused buffer.
trait Rows {
    /// Number of rows.
    fn len(&self) -> usize;
    /// Append row `i`'s cells to `buf`, pushing the end of each cell in `buf` onto `ends`.
    fn row(&mut self, i: usize, buf: &mut String, ends: &mut Vec<usize>);
}

/// Rows held as cells.
struct SliceRows<'a, S>(&'a [Vec<S>]);

impl<S: AsRef<str>> Rows for SliceRows<'_, S> {
    fn len(&self) -> usize {
        self.0.len()
    }

    fn row(&mut self, i: usize, buf: &mut String, ends: &mut Vec<usize>) {
        for c in &self.0[i] {
            buf.push_str(c.as_ref());
            ends.push(buf.len());
        }
    }
}

/// The rows of the group table: `SG`, bodies, `Nm`, inputs, level, type, from, internal, to.
struct GroupRows<'a> {
    groups: &'a [crate::structure::Group],
    /// The body list before it is wrapped.
    joined: String,
    /// Wrap widths of the list columns: bodies, from, internal, to ([`list_widths`]).
    widths: [usize; 4],
}

impl Rows for GroupRows<'_> {
    fn len(&self) -> usize {
        self.groups.len()
    }

    fn row(&mut self, i: usize, buf: &mut String, ends: &mut Vec<usize>) {
        let g = &self.groups[i];
        let mut end = |buf: &mut String| ends.push(buf.len());
        buf.push_str(&g.name);
        end(buf);
        self.joined.clear();
        for (k, b) in g.bodies.iter().enumerate() {
            if k > 0 {
                self.joined.push(',');
            }
            self.joined.push_str(b);
        }
        wrap_into(buf, &self.joined, ',', self.widths[0]);
        end(buf);
        for n in [g.nm, g.inputs as usize, g.level] {
            push_usize(buf, n);
            end(buf);
        }
        buf.push_str(&g.kind);
        end(buf);
        for (list, width) in [&g.from, &g.internal, &g.to]
            .into_iter()
            .zip(&self.widths[1..])
        {
            wrap_into(buf, dash(list), '.', *width);
            end(buf);
        }
    }
}

/// Append `n` in decimal, as `Display` writes it.
fn push_usize(s: &mut String, mut n: usize) {
    let mut digits = [0u8; 20];
    let mut k = digits.len();
    loop {
        k -= 1;
        digits[k] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    // ASCII digits: always UTF-8.
    s.push_str(std::str::from_utf8(&digits[k..]).unwrap_or_default());
}

/// Widest line of a list cell. Tables pad every row to the widest cell, so one giant group
/// (thousands of pairs) would otherwise make every row of the table as wide as its list.
const CELL_WIDTH: usize = 48;

/// Width the group table keeps within when its entries allow (as `transform`'s tables).
const TABLE_WIDTH: usize = 120;

/// Wrap widths of the group table's list columns (bodies, from, internal, to). Each list
/// wraps at [`CELL_WIDTH`] as long as the table then fits [`TABLE_WIDTH`]; otherwise the room
/// the other columns leave is shared among the lists, none narrower than its longest entry
/// (entries are never split) or its header, none wider than it needs. One pass over the
/// groups, reading lengths only.
fn list_widths(groups: &[crate::structure::Group]) -> [usize; 4] {
    let chars = |t: &str| t.chars().count();
    let digits = |n: usize| n.checked_ilog10().map_or(1, |d| d as usize + 1);
    // SG, Nm, inputs, level, type: their headers, then their widest cells.
    let mut fixed = [2usize, 2, 6, 5, 4];
    // Headers: bodies, from, internal, to.
    let mut atom = [6usize, 4, 8, 2];
    let mut natural = atom;
    // The longest piece of an entry broken after its `&` (a pair's two bodies apart): the
    // narrowest a list column can be when whole entries do not fit.
    let mut piece = atom;
    for g in groups {
        fixed[0] = fixed[0].max(chars(&g.name));
        fixed[1] = fixed[1].max(digits(g.nm));
        fixed[2] = fixed[2].max(digits(g.inputs as usize));
        fixed[3] = fixed[3].max(digits(g.level));
        fixed[4] = fixed[4].max(chars(&g.kind));
        // The widest line of each list wrapped at CELL_WIDTH, as `wrap_into` wraps it.
        let (mut line, mut widest) = (0, 0);
        for (k, b) in g.bodies.iter().enumerate() {
            let n = chars(b) + usize::from(k + 1 < g.bodies.len());
            atom[0] = atom[0].max(n);
            if line > 0 && line + n > CELL_WIDTH {
                line = 0;
            }
            line += n;
            widest = widest.max(line);
        }
        natural[0] = natural[0].max(widest);
        for (c, list) in [&g.from, &g.internal, &g.to].into_iter().enumerate() {
            let (mut line, mut widest) = (0, 0);
            for entry in dash(list).split_inclusive('.') {
                let n = chars(entry);
                atom[c + 1] = atom[c + 1].max(n);
                for p in entry.split_inclusive('&') {
                    piece[c + 1] = piece[c + 1].max(chars(p));
                }
                if line > 0 && line + n > CELL_WIDTH {
                    line = 0;
                }
                line += n;
                widest = widest.max(line);
            }
            natural[c + 1] = natural[c + 1].max(widest);
        }
    }
    piece[0] = atom[0];
    for c in 0..4 {
        natural[c] = natural[c].max(atom[c]);
    }
    // Nine columns: two spaces of padding each and eight separators.
    let room = TABLE_WIDTH.saturating_sub(fixed.iter().sum::<usize>() + 2 * 9 + 8);
    if natural.iter().sum::<usize>() <= room {
        return [CELL_WIDTH; 4];
    }
    // Whole entries when they fit, else entries broken after their `&` where needed.
    let mut width = if atom.iter().sum::<usize>() <= room {
        atom
    } else {
        piece
    };
    let mut left = room.saturating_sub(width.iter().sum());
    while left > 0 {
        let open: Vec<usize> = (0..4).filter(|&c| width[c] < natural[c]).collect();
        if open.is_empty() {
            break;
        }
        let share = (left / open.len()).max(1);
        for c in open {
            let add = share.min(natural[c] - width[c]).min(left);
            width[c] += add;
            left -= add;
        }
    }
    width
}

/// Append a list (`9&10S.9&13R.` or `3,5,7`) to `out`, broken into lines of at most `width`
/// characters after a separator, so that no entry is split.
fn wrap_into(out: &mut String, text: &str, sep: char, width: usize) {
    // Never more than one line (characters are at most bytes): nothing to break.
    if text.len() <= width {
        out.push_str(text);
        return;
    }
    let mut line = 0;
    let mut put = |out: &mut String, piece: &str| {
        let n = piece.chars().count();
        if line > 0 && line + n > width {
            out.push('\n');
            line = 0;
        }
        out.push_str(piece);
        line += n;
    };
    for entry in text.split_inclusive(sep) {
        // An entry wider than a column narrowed to fit 120 breaks after its `&`.
        if width < CELL_WIDTH && entry.chars().count() > width {
            entry.split_inclusive('&').for_each(|p| put(out, p));
        } else {
            put(out, entry);
        }
    }
}

/// Append `header` and `rows` as [`super::new_table`] renders them (without the final newline),
/// writing the lines straight into `out`. comfy-table builds every padded line of every cell as
/// its own string and measures each with Unicode segmentation: seconds and hundreds of
/// megabytes for the 250,000 groups of a 10^6-body mechanism. Printable ASCII (the ids of
/// every generated and bundled mechanism) is one column per byte, so the layout is computed
/// directly; anything else (wide or combining characters, control characters) goes through
/// comfy-table itself, so the bytes are the same either way.
#[cfg(test)]
fn plain_table<S: AsRef<str>>(out: &mut String, header: &[S], rows: &[Vec<S>]) {
    let _ = plain_table_with(out, header, &mut SliceRows(rows), &mut |_: &mut String| {
        Ok(())
    });
}

/// [`plain_table`] over rows made on demand (see [`Rows`]), calling `flush` after each row.
fn plain_table_with<S: AsRef<str>>(
    out: &mut String,
    header: &[S],
    rows: &mut impl Rows,
    flush: &mut Flush<'_>,
) -> std::io::Result<()> {
    let ncols = header.len();
    let simple = |c: &str| c.bytes().all(|b| b == b'\n' || (0x20..0x7f).contains(&b));
    let mut fits = header.iter().all(|c| simple(c.as_ref()));
    let mut width = vec![1usize; ncols];
    let mut buf = String::new();
    let mut ends: Vec<usize> = Vec::with_capacity(ncols);
    let cells = |rows: &mut dyn Rows, i: usize, buf: &mut String, ends: &mut Vec<usize>| {
        buf.clear();
        ends.clear();
        rows.row(i, buf, ends);
    };
    // Cell `c` of the row in the buffer.
    let cell = |ends: &[usize], c: usize| (if c == 0 { 0 } else { ends[c - 1] })..ends[c];
    if fits {
        for c in 0..ncols {
            for line in header[c].as_ref().split('\n') {
                width[c] = width[c].max(line.len());
            }
        }
        for i in 0..rows.len() {
            cells(rows, i, &mut buf, &mut ends);
            if ends.len() != ncols || !simple(&buf) {
                fits = false;
                break;
            }
            for c in 0..ncols {
                for line in buf[cell(&ends, c)].split('\n') {
                    width[c] = width[c].max(line.len());
                }
            }
        }
    }
    // comfy-table keeps widths in u16: leave such tables to it.
    if !fits || width.iter().any(|&w| w + 2 > usize::from(u16::MAX)) {
        let mut t = super::new_table();
        t.set_header(header.iter().map(|c| c.as_ref().to_string()));
        for i in 0..rows.len() {
            cells(rows, i, &mut buf, &mut ends);
            t.add_row((0..ends.len()).map(|c| buf[cell(&ends, c)].to_string()));
        }
        let _ = write!(out, "{t}");
        return flush(out);
    }
    let rule: usize = width.iter().map(|w| w + 2).sum::<usize>() + ncols.saturating_sub(1);
    let hr = |out: &mut String| out.extend(std::iter::repeat_n('─', rule));
    // Where the next line of each cell starts (past its end: no line left).
    let mut cursor: Vec<usize> = Vec::with_capacity(ncols);
    let mut put_row = |out: &mut String, buf: &str, ends: &[usize]| {
        cursor.clear();
        cursor.extend((0..ncols).map(|c| cell(ends, c).start));
        let height = (0..ncols)
            .map(|c| buf[cell(ends, c)].bytes().filter(|&b| b == b'\n').count() + 1)
            .max()
            .unwrap_or(0);
        for _ in 0..height {
            out.push('\n');
            for c in 0..ncols {
                if c > 0 {
                    out.push(' ');
                }
                let (at, end) = (cursor[c], ends[c]);
                // The lines `split('\n')` gives, then empty ones.
                let text = if at > end {
                    ""
                } else {
                    let stop = buf[at..end].find('\n').map_or(end, |k| at + k);
                    cursor[c] = stop + 1;
                    &buf[at..stop]
                };
                out.push(' ');
                out.push_str(text);
                out.extend(std::iter::repeat_n(' ', width[c] - text.len() + 1));
            }
        }
    };
    hr(out);
    buf.clear();
    ends.clear();
    for h in header {
        buf.push_str(h.as_ref());
        ends.push(buf.len());
    }
    put_row(out, &buf, &ends);
    out.push('\n');
    hr(out);
    for i in 0..rows.len() {
        cells(rows, i, &mut buf, &mut ends);
        put_row(out, &buf, &ends);
        flush(out)?;
    }
    out.push('\n');
    hr(out);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn comfy(header: &[String], rows: &[Vec<String>]) -> String {
        let mut t = crate::report::new_table();
        t.set_header(header.to_vec());
        for r in rows {
            t.add_row(r.clone());
        }
        t.to_string()
    }

    #[test]
    fn plain_table_is_comfy_table_byte_for_byte() {
        let mut rng = crate::rng::SplitMix64::new(3);
        let alphabet = ["a", "7", "&", ".", ",", "-", " ", "\n", "", "é", "漢", "\t"];
        for round in 0..400 {
            let ncols = 1 + rng.below(5) as usize;
            let nrows = rng.below(6) as usize;
            let ascii_only = round % 2 == 0;
            let mut cell = || {
                let n = rng.below(12) as usize;
                (0..n)
                    .map(|_| {
                        let k = rng.below(if ascii_only { 9 } else { 12 }) as usize;
                        alphabet[k]
                    })
                    .collect::<String>()
            };
            let header: Vec<String> = (0..ncols).map(|_| cell()).collect();
            let rows: Vec<Vec<String>> = (0..nrows)
                .map(|_| (0..ncols).map(|_| cell()).collect())
                .collect();
            let mut mine = String::new();
            plain_table(&mut mine, &header, &rows);
            assert_eq!(
                mine,
                comfy(&header, &rows),
                "round {round}: {header:?} {rows:?}"
            );
        }
    }
    /// Entries too long to fit whole (a Delta robot's `proximal_link_1&distal_link_1S.`, 32
    /// characters, three list columns of them: 156 columns) break after their `&` and the
    /// table fits 120; every piece is whole.
    #[test]
    fn entries_too_long_to_fit_whole_break_after_their_ampersand() {
        let pair = |a: &str, b: &str, t: &str| format!("{a}&{b}{t}.");
        let groups: Vec<crate::structure::Group> = (1..=3)
            .map(|k| {
                let arm = format!("proximal_link_{k}");
                crate::structure::Group {
                    name: format!("SG-{k}"),
                    bodies: vec![arm.clone()],
                    nm: 1,
                    level: 1,
                    inputs: 1,
                    kind: "1R3D".into(),
                    in_library: true,
                    depends_on: Vec::new(),
                    from: pair(&arm, "base_link", "R"),
                    internal: pair(&arm, "distal_link_0", "S"),
                    to: pair(&arm, &format!("distal_link_{k}"), "S")
                        + &pair(&arm, &format!("distal_link_{}", k + 3), "S"),
                }
            })
            .collect();
        let widths = list_widths(&groups);
        assert!(
            widths[1] < "proximal_link_1&base_linkR.".len(),
            "{widths:?}"
        );
        let mut rows = GroupRows {
            groups: &groups,
            joined: String::new(),
            widths,
        };
        let header = [
            "SG", "bodies", "Nm", "inputs", "level", "type", "from", "internal", "to",
        ];
        let mut out = String::new();
        plain_table_with(&mut out, &header, &mut rows, &mut |_: &mut String| Ok(()))
            .expect("renders");
        let widest = out.lines().map(|l| l.chars().count()).max().unwrap_or(0);
        assert!(widest <= 120, "{widest}:\n{out}");
        for piece in [
            "proximal_link_1&",
            "base_linkR.",
            "distal_link_4S.",
            "distal_link_0S.",
        ] {
            assert!(out.contains(piece), "{piece}:\n{out}");
        }
    }

    /// Modelica's EngineV6 (long body and joint ids) made a 146-column group table; it now
    /// fits 120, no list entry split; a table that fitted stays byte for byte what it was.
    #[test]
    fn the_group_table_fits_120_columns_when_its_entries_allow() {
        let widest = |t: &str| t.lines().map(|l| l.chars().count()).max().unwrap_or(0);
        let lib = crate::structure::Library::builtin();
        for (name, before) in [("msl-engine-v6", 146), ("stewart", 167), ("four-bar", 0)] {
            let (file, text) = crate::examples::find(name).expect("bundled");
            let m = crate::format::load(file, text, crate::format::Format::Toml).expect("valid");
            let a = crate::structure::analyze(&m, &crate::structure::Options::default(), &lib)
                .expect("analyses");
            let t = table(&a);
            let groups: String = t
                .lines()
                .skip_while(|l| !l.starts_with(" SG "))
                .take_while(|l| !l.starts_with(" SG type"))
                .collect::<Vec<_>>()
                .join("\n");
            assert!(widest(&groups) <= 120, "{name}:\n{t}");
            // Every entry of every list whole in one cell line.
            for g in &a.groups {
                for entry in g.from.split_inclusive('.').chain(g.to.split_inclusive('.')) {
                    assert!(groups.contains(entry), "{name}: {entry} split");
                }
            }
            if before == 0 {
                // Fitted already: the widths are the old fixed ones.
                assert_eq!(list_widths(&a.groups), [CELL_WIDTH; 4], "{name}");
            } else {
                assert!(list_widths(&a.groups).iter().any(|&w| w < CELL_WIDTH));
            }
        }
    }
}
