//! The budget of a factorization: work charged to a meter, memory checked against a limit.

use crate::budget::{Budget, BudgetExceeded, Meter};

/// Bytes of one field element (and of one index) in the memory estimates.
pub(super) const FP_BYTES: u64 = 8;

/// The budget of one factorization: work charged to a meter, memory checked against the
/// budget's limit, `what` naming the matrix in the message.
pub struct Limits<'a> {
    /// The memory limit.
    pub budget: &'a Budget,
    /// The work meter of the analysis.
    pub meter: &'a mut Meter,
    /// What is being factorized, for the message.
    pub what: &'a dyn Fn() -> String,
}

impl Limits<'_> {
    pub(super) fn charge(&mut self, work: u64, bytes: u64) -> Result<(), BudgetExceeded> {
        self.meter.charge(work)?;
        self.budget.check_memory(bytes, self.what)
    }
}
