//! Generators of mesh inputs (see the module above).
