//! Renders, animations and plots of a `drape run` output directory, without
//! ParaView.
//!
//! The crate reads the files of the output directory (`fields.pvd`,
//! `fields/step_NNNNNN.vtu`, `history.csv`, `summary.json`) — it does not
//! depend on the `drape` library — and writes:
//!
//! - [`render`] with [`Layout::Single`]: the deformed fabric of one frame as
//!   filled triangles coloured by a [`Field`] (viridis; the wrinkle state in
//!   three colours), z-buffered, anti-aliased by supersampling, lightly
//!   shaded, seen from the top, the side or in perspective ([`View`]), with
//!   the obstacles of the scenario in grey, a title with the time and a
//!   colour bar with the field's name, unit, minimum and maximum;
//! - [`Layout::Grid`]: about six frames spread over the run in one figure,
//!   with one colour scale and one camera;
//! - [`Layout::Animation`]: every frame as an animated GIF;
//! - [`plot`]: the time histories (monitored heights, energies, Newton
//!   iterations, contact force, wrinkling state, smallest gap);
//! - [`test_figure`]: a drape test's specimens, their shadows overlaid and
//!   the histogram of their fold counts (the caller measures them).
//!
//! Elements of order 2 and 3 are drawn as 4 and 9 flat sub-triangles
//! through their nodes, outlined along the element's edges.
//!
//! Obstacles are not described by the output directory: they are read from
//! the `[[obstacle]]` tables of a scenario file ([`RenderOptions::scenario`],
//! by default `DIR/scenario.toml` if it exists), moved by their velocity to
//! the frame's time, and clipped to a box around the fabric. Mesh obstacles
//! are not drawn (a notice says so).
//!
//! ```no_run
//! use drape_render::{render, plot, Layout, RenderOptions, View};
//! use std::path::Path;
//!
//! let dir = Path::new("out/fabric-on-pedestal");
//! let opts = RenderOptions {
//!     view: View::Perspective,
//!     scenario: Some("examples/fabric-on-pedestal.toml".into()),
//!     output: Some("pedestal.png".into()),
//!     ..RenderOptions::default()
//! };
//! let report = render(dir, &opts)?;
//! println!("range {:?}", report.range);
//! let grid = RenderOptions { layout: Layout::Grid { panels: 6 }, output: None, ..opts };
//! render(dir, &grid)?; // out/fabric-on-pedestal/render-grid.png
//! plot(dir, Path::new("history.png"), 1200, 900)?;
//! # Ok::<(), drape_render::RenderError>(())
//! ```
#![warn(missing_docs)]

/// `clap::ValueEnum` for a choice that lists itself (`ALL`) and names
/// itself (`name()`): the command line accepts exactly those names.
#[cfg(feature = "clap")]
macro_rules! value_enum_by_name {
    ($choice:ty) => {
        impl clap::ValueEnum for $choice {
            fn value_variants<'a>() -> &'a [Self] {
                &<$choice>::ALL
            }

            fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
                Some(clap::builder::PossibleValue::new(self.name()))
            }
        }
    };
}
#[cfg(feature = "clap")]
pub(crate) use value_enum_by_name;

mod anim;
mod colorbar;
mod colormap;
mod error;
mod field;
mod geom;
mod image;
mod outdir;
mod overlay;
mod plot;
mod raster;
mod render;
mod scenario;
mod specimens;
mod text;
pub mod vtu;

pub use anim::gif_info;
pub use colormap::{WRINKLE_COLOURS, viridis};
pub use error::{RenderError, Result};
pub use field::{Field, FieldValues, WRINKLE_STATES, format_value};
pub use image::RgbImage;
pub use outdir::{FrameEntry, FrameSelect, History, OutputDir};
pub use overlay::Circle;
pub use plot::HISTORY_COLUMNS;
pub use plot::{ExtraPanel, PlotReport, plot, plot_image, plot_image_with, plot_with};
pub use raster::View;
pub use render::{
    Layout, MAX_RENDER_BYTES, Projection, RenderOptions, RenderReport, default_output, render,
    render_bytes, render_image,
};
pub use scenario::{Obstacle, Shape, monitor_names, parse_obstacles, read_obstacles};
pub use specimens::{TestFigure, test_figure};
