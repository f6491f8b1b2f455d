//! The structural analysis as tables for people, in the layout of the paper's Table 8 (groups)
//! and Table 9 (types against the library), followed by the findings.

use crate::structure::{Analysis, Status};
use std::borrow::Cow;
use std::fmt::Write;

fn dash(s: &str) -> &str {
    if s.is_empty() { "-" } else { s }
}

/// Render the analysis.
pub fn table(a: &Analysis) -> String {
    let mut out = String::new();
    let status = match a.status {
        Status::Determined => "determined",
        Status::Overdetermined => "over-determined",
        Status::Underdetermined => "under-determined",
        Status::Mixed => "not determined (over- and under-determined parts)",
    };
    let _ = writeln!(
        out,
        "{}: {} structural group(s) on {} level(s); mobility {}, inputs {}; {}{}",
        a.name,
        a.groups.len(),
        a.levels,
        a.mobility.count,
        a.mobility.inputs,
        status,
        if a.count_only { " (count only)" } else { "" }
    );
    if let Some(g) = &a.geometry {
        let _ = writeln!(out, "{}", g.line());
    }
    if !a.groups.is_empty() {
        // Cells borrowed from the groups where they need no change (a 10^6-body analysis has
        // 250,000 rows: nine new strings a row were a third of the rendering).
        let rows: Vec<Vec<Cow<'_, str>>> = a
            .groups
            .iter()
            .map(|g| {
                vec![
                    Cow::Borrowed(g.name.as_str()),
                    Cow::Owned(wrap(&g.bodies.join(","), ',').into_owned()),
                    Cow::Owned(g.nm.to_string()),
                    Cow::Owned(g.inputs.to_string()),
                    Cow::Owned(g.level.to_string()),
                    Cow::Borrowed(g.kind.as_str()),
                    wrap(dash(&g.from), '.'),
                    wrap(dash(&g.internal), '.'),
                    wrap(dash(&g.to), '.'),
                ]
            })
            .collect();
        let header = [
            "SG", "bodies", "Nm", "inputs", "level", "type", "from", "internal", "to",
        ]
        .map(Cow::Borrowed);
        plain_table(&mut out, &header, &rows);
        out.push('\n');
        drop(rows);
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
        plain_table(&mut out, &header, &rows);
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
            sizes.join(", ")
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
            "isolated freedoms (no input can drive them, left out): {}",
            list.join(", ")
        );
    }
    if let Some(d) = &a.diagnosis {
        if !d.unsolved.is_empty() {
            let _ = writeln!(out, "bodies left unsolved: {}", d.unsolved.join(", "));
        }
        for n in &d.notes {
            let _ = writeln!(out, "- {n}");
        }
    } else {
        for n in &a.notes {
            let _ = writeln!(out, "- {n}");
        }
    }
    out
}

/// Widest line of a list cell. Tables pad every row to the widest cell, so one giant group
/// (thousands of pairs) would otherwise make every row of the table as wide as its list.
const CELL_WIDTH: usize = 48;

/// Break a list (`9&10S.9&13R.` or `3,5,7`) into lines of at most [`CELL_WIDTH`] characters,
/// after a separator, so that no entry is split.
fn wrap(text: &str, sep: char) -> Cow<'_, str> {
    // Never more than one line (characters are at most bytes): nothing to break.
    if text.len() <= CELL_WIDTH {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + text.len() / CELL_WIDTH + 1);
    let mut line = 0;
    for entry in text.split_inclusive(sep) {
        let n = entry.chars().count();
        if line > 0 && line + n > CELL_WIDTH {
            out.push('\n');
            line = 0;
        }
        out.push_str(entry);
        line += n;
    }
    Cow::Owned(out)
}

/// Append `header` and `rows` as [`super::new_table`] renders them (without the final newline),
/// writing the lines straight into `out`. comfy-table builds every padded line of every cell as
/// its own string and measures each with Unicode segmentation: seconds and hundreds of
/// megabytes for the 250,000 groups of a 10^6-body mechanism. Printable ASCII (the ids of
/// every generated and bundled mechanism) is one column per byte, so the layout is computed
/// directly; anything else (wide or combining characters, control characters) goes through
/// comfy-table itself, so the bytes are the same either way.
fn plain_table<S: AsRef<str>>(out: &mut String, header: &[S], rows: &[Vec<S>]) {
    let ncols = header.len();
    let simple = |c: &S| {
        c.as_ref()
            .bytes()
            .all(|b| b == b'\n' || (0x20..0x7f).contains(&b))
    };
    let fits = header.iter().all(simple)
        && rows
            .iter()
            .all(|r| r.len() == ncols && r.iter().all(simple));
    let mut width = vec![1usize; ncols];
    if fits {
        for row in std::iter::once(header).chain(rows.iter().map(Vec::as_slice)) {
            for (c, cell) in row.iter().enumerate() {
                for line in cell.as_ref().split('\n') {
                    width[c] = width[c].max(line.len());
                }
            }
        }
    }
    // comfy-table keeps widths in u16: leave such tables to it.
    if !fits || width.iter().any(|&w| w + 2 > usize::from(u16::MAX)) {
        let mut t = super::new_table();
        t.set_header(header.iter().map(|c| c.as_ref().to_string()));
        for r in rows {
            t.add_row(r.iter().map(|c| c.as_ref().to_string()));
        }
        let _ = write!(out, "{t}");
        return;
    }
    let rule: usize = width.iter().map(|w| w + 2).sum::<usize>() + ncols.saturating_sub(1);
    let hr = |out: &mut String| out.extend(std::iter::repeat_n('─', rule));
    let put_row = |out: &mut String, row: &[S]| {
        let mut lines: Vec<std::str::Split<'_, char>> =
            row.iter().map(|c| c.as_ref().split('\n')).collect();
        let height = row
            .iter()
            .map(|c| c.as_ref().split('\n').count())
            .max()
            .unwrap_or(0);
        for _ in 0..height {
            out.push('\n');
            for (c, it) in lines.iter_mut().enumerate() {
                if c > 0 {
                    out.push(' ');
                }
                let text = it.next().unwrap_or("");
                out.push(' ');
                out.push_str(text);
                out.extend(std::iter::repeat_n(' ', width[c] - text.len() + 1));
            }
        }
    };
    hr(out);
    put_row(out, header);
    out.push('\n');
    hr(out);
    for r in rows {
        put_row(out, r);
    }
    out.push('\n');
    hr(out);
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
}
