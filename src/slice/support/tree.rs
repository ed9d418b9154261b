//! The tree style (being written): for now the grid's paths.

use super::areas::Areas;
use super::{Input, LayerSupport, Options};

pub(crate) fn paths(o: &Options, input: &Input, areas: &Areas) -> Vec<LayerSupport> {
    super::grid::paths(o, input, areas)
}
