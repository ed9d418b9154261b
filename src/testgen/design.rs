//! Generators of design inputs (see the module above).
