//! How the set-up's passes report their progress: the solver core calls an
//! observer between chunks of work, and the command line prints it (the pass,
//! how far, an ETA). The core stays free of terminals and clocks.

/// A pass of the set-up, before the first shot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// Receivers cut along contact and shadow lines (`mesh::contact`), in
    /// polygons examined.
    ContactCuts,
    /// Polygons meshed into patches and elements.
    Meshing,
    /// The materials, the patches' light and the budget's check, in one step.
    SolverState,
    /// The visibility hierarchy over the mesh, in one step.
    Occluder,
    /// Vertices probed for whether they are hidden (`solve::hidden`).
    HiddenVertices,
    /// The patches' gather weights and the vertices that share samples
    /// (`solve::twins`, `solve::sites`), in one step.
    SharedSamples,
}

impl Pass {
    /// What the pass does, for a progress line.
    pub fn name(self) -> &'static str {
        match self {
            Pass::ContactCuts => "contact cuts",
            Pass::Meshing => "meshing",
            Pass::SolverState => "solver state",
            Pass::Occluder => "visibility hierarchy",
            Pass::HiddenVertices => "hidden vertices",
            Pass::SharedSamples => "weights and shared samples",
        }
    }

    /// What its units count.
    pub fn unit(self) -> &'static str {
        match self {
            Pass::ContactCuts | Pass::Meshing => "polygons",
            Pass::SolverState | Pass::Occluder | Pass::SharedSamples => "steps",
            Pass::HiddenVertices => "vertices",
        }
    }
}

/// Told, from the calling thread, how far each pass has come: `done` of
/// `total` units, `done == total` once when it ends.
pub trait Observer {
    fn advance(&mut self, pass: Pass, done: u64, total: u64);
}

/// An observer that ignores everything (tests, benchmarks, library use).
pub struct Quiet;

impl Observer for Quiet {
    fn advance(&mut self, _: Pass, _: u64, _: u64) {}
}

/// Units of work between two reports: small enough for a report a second
/// on a large scene, large enough that the parallel chunks stay busy.
pub const CHUNK: usize = 8192;
