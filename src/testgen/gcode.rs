//! Generators of gcode inputs (see the module above).
