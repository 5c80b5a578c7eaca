//! Empty space for cones to skip (not in the paper): per cell of the grid, how far the
//! nearest filled voxel is (glsl/empty_space.comp). A cone step in empty space reads nothing
//! (its samples are transparent black), yet a narrow cone through an open scene spends most
//! of its steps there; with the distance it jumps to where its footprint could next touch a
//! surface (glsl/cone_tracing.glsl).

use super::volumes::Volumes;
use crate::vk::{Bindings, Context, Graph, Pass, Usage, VkResult};
use std::sync::Arc;

pub struct EmptySpace {
    cells: Pass,
    /// The distance transform along one axis (push constant: the axis).
    axis: Pass,
}

impl EmptySpace {
    /// None without the volume (--paper).
    pub fn new(ctx: &Arc<Context>, volumes: &Volumes) -> VkResult<Option<EmptySpace>> {
        let Some(empty) = &volumes.empty_space else {
            return Ok(None);
        };
        let cells = Bindings::new()
            .image("radiance", &volumes.radiance, Usage::Read)
            .image("empty_space", empty, Usage::Write);
        let cells = Pass::compute(ctx, "empty_space.comp", &[], cells, 4)?;
        let axis = Bindings::new().image("empty_space", empty, Usage::ReadWrite);
        let axis = Pass::compute(ctx, "empty_space.comp:AXIS", &[], axis, 4)?;
        Ok(Some(EmptySpace { cells, axis }))
    }

    /// Which cells hold a filled voxel, then each cell's distance to the nearest that does,
    /// along x, y and z in turn.
    pub fn record(&self, ctx: &Context, g: &mut Graph, volumes: &Volumes, name: &str) {
        let m = volumes.grid.empty_space_resolution();
        let cell = volumes.grid.empty_space_cell();
        let groups = |n: u32| [n.div_ceil(64), 1, 1];
        let push = cell.to_le_bytes();
        // One name for the four dispatches, as the mip levels share theirs.
        self.cells
            .record_dispatch(ctx, g, name, &[], &push, groups(m * m * m));
        for axis in 0u32..3 {
            let push = axis.to_le_bytes();
            self.axis
                .record_dispatch(ctx, g, name, &[], &push, groups(m * m));
        }
    }
}
