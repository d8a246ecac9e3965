//! URDF in ([`read`]: links, their mesh collisions or visuals, joints) and out ([`write`]:
//! the original text with each link's mesh collisions replaced by primitives, everything else
//! byte for byte; or a URDF made from the links and joints of another format).
mod read;
mod write;

use std::ops::Range;

pub(crate) use read::parse;
pub(crate) use write::to_urdf;

/// What the URDF writer edits in the text it was read from.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Source {
    /// The file's text.
    pub(crate) text: String,
    /// By link index: where its collisions are.
    pub(crate) links: Vec<LinkSites>,
}

/// A link's mesh `<collision>` elements and where new ones go when it has none.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct LinkSites {
    /// Byte ranges of the mesh `<collision>` elements, and whether the link's primitives
    /// replace each (not a mesh of a format bvseg cannot read, which stays).
    pub(crate) collisions: Vec<(Range<usize>, bool)>,
    /// Where new collisions go when there is nothing to replace (before `</link>`).
    pub(crate) insert_at: Option<usize>,
}
