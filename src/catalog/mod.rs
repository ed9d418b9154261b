//! The catalog, above the job kinds: the schema the page reads ([`schema`]), share links
//! ([`share`]) and the design checked against the kinds (reading, changes, defaults).

mod documents;
pub mod schema;
pub mod share;
