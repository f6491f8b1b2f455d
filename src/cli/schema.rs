//! `mbsa schema`: the JSON Schema of the mechanism file format, or of a JSON report.

use super::{Failure, emit};
use clap::ValueEnum;
use mbsa::report::schema::Report;

/// What `mbsa schema` describes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Output {
    /// The mechanism file format (for editor completion).
    Input,
    /// `mbsa mobility --format json`.
    Mobility,
    /// `mbsa analyze --format json`.
    Analyze,
    /// `mbsa rigid --format json`.
    Rigid,
    /// `mbsa transform --format json`.
    Transform,
    /// One line of `mbsa transform --format jsonl`.
    TransformJsonl,
    /// One line of a `mbsa transform --partition` shard.
    TransformShard,
    /// `mbsa solve --format json`.
    Solve,
    /// `mbsa check --format json`.
    Check,
    /// One line of `mbsa check --format jsonl`.
    CheckJsonl,
    /// `mbsa cut --format json`.
    Cut,
}

/// Print the schema of `output`.
pub fn run(output: Output) -> Result<(), Failure> {
    let report = match output {
        Output::Input => return emit(&mbsa::report::json::plain(&mbsa::format::schema())),
        Output::Mobility => Report::Mobility,
        Output::Analyze => Report::Analyze,
        Output::Rigid => Report::Rigid,
        Output::Transform => Report::Transform,
        Output::TransformJsonl => Report::TransformJsonl,
        Output::TransformShard => Report::TransformShard,
        Output::Solve => Report::Solve,
        Output::Check => Report::Check,
        Output::CheckJsonl => Report::CheckJsonl,
        Output::Cut => Report::Cut,
    };
    emit(&mbsa::report::json::plain(&mbsa::report::schema::schema(
        report,
    )))
}
