//! Reading a mechanism text into the value tree ([`super::tree`]): the whole-text readers of
//! each format, and [`Lazy`], which drives the reader (whole-text or fast) that gives the items
//! of a deferred joint list one at a time.

mod json_tree;
mod toml_tree;
mod yaml_tree;

pub(crate) use json_tree::{json_check, parse_json_resume, parse_json_tree};
#[cfg(test)]
pub(crate) use toml_tree::parse_toml_serial;
pub(crate) use toml_tree::{parse_toml, parse_toml_lazy};
pub(crate) use yaml_tree::{
    YamlReader, parse_yaml, parse_yaml_fast, parse_yaml_lazy, parse_yaml_resume,
};

use super::error::LoadError;
use super::fast_toml::{JointTables, Stopped, for_each_table};
use super::fast_yaml::Items;
use super::tree::{Node, Value, syntax};
use std::ops::Range;
use toml_tree::JOINT_HEADER;

/// Where the items of a [`Value::Deferred`] list come from.
pub(crate) enum Lazy<'a> {
    /// Nothing deferred.
    None,
    /// JSON: the list's text (from `[` to `]`), parsed item by item.
    Json {
        text: &'a str,
        span: Range<usize>,
        /// The objects directly in the list, counted while it was skipped.
        items: usize,
    },
    /// JSON whose joint list is the last top-level key ([`parse_json_resume`]): the items
    /// read from `pos` (just past the list's `[`), then the end of the text checked.
    JsonResume {
        text: &'a str,
        pos: usize,
        /// At least the objects in the list (every `{` from it on).
        items: usize,
    },
    /// TOML: the joints of the first piece, then later pieces of the text (each starts with a
    /// `[[joint]]` header and holds only joints), parsed in parallel a few at a time. A piece
    /// that holds anything else, or fails to parse, sets `fallback`: the caller then reads the
    /// whole text again without deferring.
    Toml {
        text: &'a str,
        first: Vec<Node<'a>>,
        rest: Vec<Range<usize>>,
        fallback: &'a std::sync::atomic::AtomicBool,
    },
    /// YAML: the text is read a second time, the items of the top-level joint list built
    /// one at a time (the first read built the rest, skipping them).
    Yaml { text: &'a str },
    /// YAML whose joint list is the last top-level key: the reader that stopped at the list
    /// reads on, item by item ([`parse_yaml_resume`]); anything after the list is an error
    /// (the caller then reads the text again).
    YamlResume(Box<YamlReader<'a>>),
    /// YAML whose joint list is the last top-level key, its items read by
    /// [`super::fast_yaml`] (a shape it does not read is an error: the caller then reads the
    /// text with saphyr).
    YamlLines { text: &'a str, items: Items<'a> },
    /// TOML read by [`super::fast_toml`]: its `[[joint]]` tables, read one at a time. A table
    /// it does not read is an error (the caller then reads the text with the toml crate).
    TomlLines { text: &'a str, joints: JointTables },
}

impl<'a> Lazy<'a> {
    /// About how many items `list` holds (to size the joint vector once: growing a vector of
    /// a million joints by doubling holds both copies at once). Counted, not parsed: the
    /// `[[joint]]` headers of a TOML file, the `"bodies"` keys of a JSON list; bounded by the
    /// text's length, so a wrong guess costs little.
    pub(crate) fn len_hint(&self, list: &Value<'a>) -> usize {
        match (list, self) {
            (Value::Seq(items), _) => items.len(),
            (Value::Deferred, Lazy::Json { items, .. } | Lazy::JsonResume { items, .. }) => *items,
            (Value::Deferred, Lazy::TomlLines { joints, .. }) => joints.count,
            (Value::Deferred, Lazy::Yaml { text }) => text.matches("bodies").count(),
            (Value::Deferred, Lazy::YamlResume(r)) => r.text().matches("bodies").count(),
            (Value::Deferred, Lazy::YamlLines { text, .. }) => text.matches("bodies").count(),
            // Every header but one at the very start follows a line break.
            (Value::Deferred, Lazy::Toml { text, .. }) => text.matches(JOINT_HEADER).count() + 1,
            _ => 0,
        }
    }

    /// Whether an error of the model read from this source is thrown away: the fast readers'
    /// (the caller then reads the text again by a reader that reports every error, located).
    /// What only locates an error need not be kept then.
    pub(crate) fn errors_discarded(&self) -> bool {
        matches!(
            self,
            Lazy::TomlLines { .. }
                | Lazy::YamlLines { .. }
                | Lazy::YamlResume(_)
                | Lazy::JsonResume { .. }
        )
    }

    /// Call `f` on every item of `list` (a `Seq`, or the `Deferred` list), in order, each item
    /// dropped (or its memory reused) after its call; stops at the first error.
    pub(crate) fn for_each(
        self,
        list: Value<'a>,
        f: &mut dyn FnMut(&Node<'a>) -> Result<(), LoadError>,
    ) -> Result<(), LoadError> {
        match (list, self) {
            (Value::Seq(items), _) => items.into_iter().try_for_each(|item| f(&item)),
            (Value::Deferred, Lazy::Json { text, span, .. }) => {
                json_tree::for_each_skipped_item(text, span, f)
            }
            (Value::Deferred, Lazy::JsonResume { text, pos, .. }) => {
                json_tree::for_each_resumed_item(text, pos, f)
            }
            (
                Value::Deferred,
                Lazy::Toml {
                    text,
                    first,
                    rest,
                    fallback,
                },
            ) => toml_tree::for_each_piece_joint(text, first, &rest, fallback, f),
            (Value::Deferred, Lazy::TomlLines { text, joints }) => for_each_table(text, joints, f)
                .map_err(|stopped| match stopped {
                    Stopped::Failed(e) => e,
                    Stopped::Declined => syntax("TOML", "read again", 0..0, "here"),
                }),
            (Value::Deferred, Lazy::Yaml { text }) => yaml_tree::yaml_joint_items(text, f),
            (Value::Deferred, Lazy::YamlLines { mut items, .. }) => loop {
                match items.next_item() {
                    Some(Some(item)) => f(&item)?,
                    Some(None) => return Ok(()),
                    None => return Err(syntax("YAML", "read again", 0..0, "here")),
                }
            },
            (Value::Deferred, Lazy::YamlResume(r)) => yaml_tree::for_each_resumed_item(*r, f),
            (Value::Deferred, Lazy::None) => Ok(()),
            (_, _) => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests;
