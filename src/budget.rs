//! Budgets: documented caps on the input size, the work and the memory of every command.
//!
//! A [`Budget`] holds three limits. Their defaults ([`Budget::DEFAULT`]) are far above what real
//! mechanisms need (a 10^6-body file is about 130 MB and analyses in seconds), so a user only
//! meets them on hostile or absurd input; there the command stops early with a
//! [`BudgetExceeded`] error that names the limit, what needed it, and the command-line flag that
//! raises it (`--max-input-bytes`, `--max-work`, `--max-memory`, or `--budget X` to scale all
//! three), instead of running for hours or aborting on a failed allocation.
//!
//! - **Input bytes** ([`Limit::InputBytes`]): the size of a mechanism or library file. Readers
//!   stop *as they read* ([`Budget::read_to_end`], which reads at most one byte past the limit),
//!   so `/dev/zero`, an endless pipe or a FIFO cost at most the limit.
//! - **Work units** ([`Limit::Work`]): a count of elementary steps (a visited edge, an
//!   eliminated entry, an enumerated candidate), roughly one to a few nanoseconds each; the
//!   default, 10^11, is minutes of work. Long loops charge a [`Meter`].
//! - **Memory** ([`Limit::Memory`]): an *estimate*, made before allocating, of the bytes a step
//!   is about to need (a dense matrix, a generated file); the default is 4 GiB.
//!
//! Library code never prints: it returns the error, and the command-line tool renders it and
//! exits with code 2.

use std::fmt;
use std::io::Read;

/// Caps on the input size, work and memory of one command (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct Budget {
    /// Largest input accepted, in bytes (mechanism files, standard input, library files).
    pub max_input_bytes: u64,
    /// Most elementary work units one analysis may spend.
    pub max_work: u64,
    /// Largest memory estimate, in bytes, one step may allocate.
    pub max_memory_bytes: u64,
}

impl Default for Budget {
    fn default() -> Budget {
        Budget::DEFAULT
    }
}

/// Which limit of a [`Budget`] was exceeded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Limit {
    /// [`Budget::max_input_bytes`].
    InputBytes,
    /// [`Budget::max_work`].
    Work,
    /// [`Budget::max_memory_bytes`].
    Memory,
}

impl Limit {
    /// The command-line flag that raises this limit.
    pub fn flag(self) -> &'static str {
        match self {
            Limit::InputBytes => "--max-input-bytes",
            Limit::Work => "--max-work",
            Limit::Memory => "--max-memory",
        }
    }

    /// The limit's name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Limit::InputBytes => "input size limit",
            Limit::Work => "work limit",
            Limit::Memory => "memory limit",
        }
    }

    fn amount(self, n: u64) -> String {
        match self {
            Limit::InputBytes | Limit::Memory => bytes_in_words(n),
            Limit::Work => format!("{} work units", count_in_words(n)),
        }
    }
}

/// A limit of the [`Budget`] was exceeded: what needed it, how much, and the allowed amount.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct BudgetExceeded {
    /// The limit.
    pub limit: Limit,
    /// What needed more (`"reading `big.toml`"`, `"the rank check"`, ...).
    pub what: String,
    /// The amount needed (a lower bound when `at_least`).
    pub needed: u64,
    /// Whether `needed` is only a lower bound (reading stopped at the limit, a count stopped).
    pub at_least: bool,
    /// The allowed amount.
    pub allowed: u64,
}

impl fmt::Display for BudgetExceeded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let needed = if self.at_least {
            format!("more than {}", self.limit.amount(self.allowed))
        } else {
            self.limit.amount(self.needed)
        };
        write!(
            f,
            "{} needs {needed}, over the {} of {}",
            self.what,
            self.limit.name(),
            self.limit.amount(self.allowed)
        )
    }
}

impl std::error::Error for BudgetExceeded {}

impl BudgetExceeded {
    /// How to raise the limit, for a `help:` line.
    pub fn help(&self) -> String {
        format!(
            "raise it with `{} N` or scale every limit with `--budget X` (e.g. `--budget 10`)",
            self.limit.flag()
        )
    }
}

impl Budget {
    /// The defaults: 256 MiB of input, 10^11 work units, 4 GiB of memory.
    pub const DEFAULT: Budget = Budget {
        max_input_bytes: 256 * 1024 * 1024,
        max_work: 100_000_000_000,
        max_memory_bytes: 4 * 1024 * 1024 * 1024,
    };

    /// No limit at all (tests, trusted callers).
    pub const UNLIMITED: Budget = Budget {
        max_input_bytes: u64::MAX,
        max_work: u64::MAX,
        max_memory_bytes: u64::MAX,
    };

    /// Every limit multiplied by `factor` (saturating; `factor` ≤ 0 or NaN gives zero limits).
    pub fn scaled(self, factor: f64) -> Budget {
        let s = |v: u64| -> u64 {
            let x = v as f64 * factor;
            if x.is_nan() || x <= 0.0 {
                0
            } else if x >= u64::MAX as f64 {
                u64::MAX
            } else {
                x as u64
            }
        };
        Budget {
            max_input_bytes: s(self.max_input_bytes),
            max_work: s(self.max_work),
            max_memory_bytes: s(self.max_memory_bytes),
        }
    }

    /// The allowed amount of `limit`.
    pub fn allowed(&self, limit: Limit) -> u64 {
        match limit {
            Limit::InputBytes => self.max_input_bytes,
            Limit::Work => self.max_work,
            Limit::Memory => self.max_memory_bytes,
        }
    }

    /// Check that `needed` of `limit` fits; `what` names what needs it.
    pub fn check(
        &self,
        limit: Limit,
        needed: u64,
        what: impl FnOnce() -> String,
    ) -> Result<(), BudgetExceeded> {
        let allowed = self.allowed(limit);
        if needed <= allowed {
            Ok(())
        } else {
            Err(BudgetExceeded {
                limit,
                what: what(),
                needed,
                at_least: false,
                allowed,
            })
        }
    }

    /// Check an input of `len` bytes.
    pub fn check_input(
        &self,
        len: u64,
        what: impl FnOnce() -> String,
    ) -> Result<(), BudgetExceeded> {
        self.check(Limit::InputBytes, len, what)
    }

    /// Check a memory estimate of `bytes` (compute it with checked or saturating arithmetic).
    pub fn check_memory(
        &self,
        bytes: u64,
        what: impl FnOnce() -> String,
    ) -> Result<(), BudgetExceeded> {
        self.check(Limit::Memory, bytes, what)
    }

    /// Check a work estimate of `units`, before starting.
    pub fn check_work(
        &self,
        units: u64,
        what: impl FnOnce() -> String,
    ) -> Result<(), BudgetExceeded> {
        self.check(Limit::Work, units, what)
    }

    /// A work meter for one analysis: charge it as the work goes.
    pub fn meter(&self, what: &'static str) -> Meter {
        Meter {
            used: 0,
            allowed: self.max_work,
            what,
        }
    }

    /// Read `reader` to its end, stopping as soon as more than [`Budget::max_input_bytes`] have
    /// come (at most one byte past the limit is read: `/dev/zero` or an endless pipe costs the
    /// limit, no more). `what` names the source in the error (`"`big.toml`"`, `"standard input"`).
    pub fn read_to_end<R: Read>(&self, reader: R, what: &str) -> Result<Vec<u8>, ReadError> {
        self.read_to_end_sized(reader, what, 0)
    }

    /// [`Budget::read_to_end`] into a buffer sized for `expected` bytes (at most the limit).
    fn read_to_end_sized<R: Read>(
        &self,
        reader: R,
        what: &str,
        expected: u64,
    ) -> Result<Vec<u8>, ReadError> {
        let limit = self.max_input_bytes;
        let mut buf = Vec::with_capacity(usize::try_from(expected.min(limit)).unwrap_or(0));
        reader
            .take(limit.saturating_add(1))
            .read_to_end(&mut buf)
            .map_err(ReadError::Io)?;
        if buf.len() as u64 > limit {
            return Err(ReadError::TooLarge(BudgetExceeded {
                limit: Limit::InputBytes,
                what: format!("reading {what}"),
                needed: buf.len() as u64,
                at_least: true,
                allowed: limit,
            }));
        }
        Ok(buf)
    }

    /// Read a file by path within the input limit: a regular file larger than the limit is
    /// refused from its metadata before reading; other files (FIFOs, devices) are read up to
    /// the limit.
    pub fn read_file(&self, path: &std::path::Path) -> Result<Vec<u8>, ReadError> {
        let file = std::fs::File::open(path).map_err(ReadError::Io)?;
        let what = format!("`{}`", path.display());
        // A regular file's length (0 for others): refused at once over the limit, else the
        // size of the buffer (read into at once, not grown by doubling and copying).
        let len = file
            .metadata()
            .ok()
            .filter(|m| m.is_file())
            .map_or(0, |m| m.len());
        if len > self.max_input_bytes {
            return Err(ReadError::TooLarge(BudgetExceeded {
                limit: Limit::InputBytes,
                what: format!("reading {what}"),
                needed: len,
                at_least: false,
                allowed: self.max_input_bytes,
            }));
        }
        self.read_to_end_sized(file, &what, len)
    }
}

/// Why [`Budget::read_to_end`] or [`Budget::read_file`] failed.
#[derive(Debug)]
pub enum ReadError {
    /// The operating system's error.
    Io(std::io::Error),
    /// The input is larger than the input limit.
    TooLarge(BudgetExceeded),
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReadError::Io(e) => e.fmt(f),
            ReadError::TooLarge(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for ReadError {}

/// Counts the work units of one analysis against [`Budget::max_work`].
#[derive(Clone, Debug)]
pub struct Meter {
    used: u64,
    allowed: u64,
    what: &'static str,
}

impl Meter {
    /// Spend `units`; an error once the total passes the limit.
    #[inline]
    pub fn charge(&mut self, units: u64) -> Result<(), BudgetExceeded> {
        self.used = self.used.saturating_add(units);
        if self.used <= self.allowed {
            Ok(())
        } else {
            Err(BudgetExceeded {
                limit: Limit::Work,
                what: self.what.to_string(),
                needed: self.used,
                at_least: true,
                allowed: self.allowed,
            })
        }
    }

    /// Units spent so far.
    pub fn used(&self) -> u64 {
        self.used
    }

    /// The units this meter allows in all (its limit).
    pub fn allowed(&self) -> u64 {
        self.allowed
    }

    /// A meter for one optional step: it starts where this one is and allows `num / den` of
    /// the units left (at least none, at most all), so that the step stops early enough to
    /// leave the rest of the analysis the remainder. Give its spending back with
    /// [`Meter::settle`].
    pub fn share(&self, num: u64, den: u64) -> Meter {
        let left = self.allowed.saturating_sub(self.used);
        let part = if den == 0 {
            left
        } else {
            // In u128: `left · num` overflows u64 for the unlimited budget.
            ((left as u128 * num as u128) / den as u128).min(left as u128) as u64
        };
        Meter {
            used: self.used,
            allowed: self.used.saturating_add(part),
            what: self.what,
        }
    }

    /// Take over what `sub` (from [`Meter::share`] of this meter) spent. A stopped step
    /// charged its last amount before doing that work, so what it really did is at most its
    /// limit: that much is charged here, and within this meter's own limit it never fails.
    pub fn settle(&mut self, sub: &Meter) {
        self.used = self.used.max(sub.used.min(sub.allowed));
    }
}

/// A count for messages: the exact integer, except a saturated `u64::MAX`, which says
/// `"more than 10^19"` (a count too large to hold is never printed as `18446744073709551615`).
pub fn count_in_words(n: u64) -> String {
    if n == u64::MAX {
        "more than 10^19".to_string()
    } else {
        n.to_string()
    }
}

/// A byte amount for messages: `"300 bytes"`, `"12.5 MiB"`, `"4 GiB"`; a saturated
/// `u64::MAX` says `"more than 10^19 bytes"`.
pub fn bytes_in_words(n: u64) -> String {
    const KIB: u64 = 1024;
    const MIB: u64 = 1024 * KIB;
    const GIB: u64 = 1024 * MIB;
    if n == u64::MAX {
        return "more than 10^19 bytes".to_string();
    }
    let (unit, name) = if n >= GIB {
        (GIB, "GiB")
    } else if n >= MIB {
        (MIB, "MiB")
    } else if n >= 10 * KIB {
        (KIB, "KiB")
    } else {
        return format!("{n} bytes");
    };
    if n.is_multiple_of(unit) {
        format!("{} {name} ({n} bytes)", n / unit)
    } else {
        format!("{:.1} {name} ({n} bytes)", n as f64 / unit as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reading_stops_at_the_limit() {
        let b = Budget {
            max_input_bytes: 1000,
            ..Budget::DEFAULT
        };
        // An endless reader: only limit + 1 bytes are read.
        let endless = std::io::repeat(b'x');
        match b.read_to_end(endless, "standard input") {
            Err(ReadError::TooLarge(e)) => {
                assert_eq!(e.limit, Limit::InputBytes);
                assert!(e.at_least);
                let msg = e.to_string();
                assert!(msg.contains("more than 1000 bytes"), "{msg}");
                assert!(e.help().contains("--max-input-bytes"));
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(b.read_to_end(&[1u8; 1000][..], "x").unwrap().len(), 1000);
    }

    /// A share stops its step within its part of what is left; settling charges the parent
    /// what the step did (at most the share's limit), never past the parent's own limit; the
    /// unlimited meter's share does not overflow.
    #[test]
    fn a_meter_share_stops_within_its_part_and_settles_in_the_parent() {
        let b = Budget {
            max_work: 1000,
            ..Budget::DEFAULT
        };
        let mut m = b.meter("x");
        m.charge(200).unwrap();
        let mut s = m.share(7, 8);
        assert_eq!((s.used(), s.allowed()), (200, 900));
        s.charge(700).unwrap();
        let e = s.charge(1).unwrap_err();
        assert_eq!((e.limit, e.allowed), (Limit::Work, 900));
        m.settle(&s);
        assert_eq!(m.used(), 900);
        m.charge(100).unwrap();
        assert!(m.charge(1).is_err());
        // A step that finished within its share hands back exactly what it spent.
        let mut m = b.meter("x");
        let mut s = m.share(1, 2);
        s.charge(300).unwrap();
        m.settle(&s);
        assert_eq!(m.used(), 300);
        let u = Budget::UNLIMITED.meter("x");
        let s = u.share(7, 8);
        assert!(s.allowed() > u64::MAX / 8 * 7 - 8);
        assert_eq!(u.share(1, 0).allowed(), u64::MAX);
    }

    #[test]
    fn meter_and_checks() {
        let b = Budget {
            max_work: 10,
            ..Budget::DEFAULT
        };
        let mut m = b.meter("the flow");
        assert!(m.charge(10).is_ok());
        let e = m.charge(1).unwrap_err();
        assert_eq!(e.limit, Limit::Work);
        assert!(
            e.to_string()
                .starts_with("the flow needs more than 10 work units")
        );
        assert!(
            Budget::DEFAULT
                .check_memory(u64::MAX, || "a matrix".into())
                .unwrap_err()
                .to_string()
                .contains("more than 10^19 bytes")
        );
    }

    #[test]
    fn scaling_saturates() {
        let b = Budget::DEFAULT.scaled(1e30);
        assert_eq!(b, Budget::UNLIMITED);
        assert_eq!(Budget::DEFAULT.scaled(2.0).max_work, 200_000_000_000);
        assert_eq!(Budget::DEFAULT.scaled(f64::NAN).max_work, 0);
    }

    #[test]
    fn words() {
        assert_eq!(count_in_words(u64::MAX), "more than 10^19");
        assert_eq!(count_in_words(64), "64");
        assert_eq!(bytes_in_words(300), "300 bytes");
        assert_eq!(
            bytes_in_words(256 * 1024 * 1024),
            "256 MiB (268435456 bytes)"
        );
    }
}
