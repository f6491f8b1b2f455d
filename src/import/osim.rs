//! stub
use super::{Builder, ImportError, Src};

pub(super) fn read(src: &Src, _doc: &roxmltree::Document) -> Result<Builder, ImportError> {
    Err(ImportError::new(format!("{}: not yet supported", src.name)))
}
