//! The geometry core of the diffuse solver: exact and sampled form factors,
//! sampling of source polygons, polygon helpers (clipping, triangulation,
//! ray/triangle) and the occlusion BVH that answers visibility rays.
//!
//! * [`formfactor`]: the exact unoccluded point-to-polygon form factor (Lambert's
//!   contour formula, Baum et al. 1989) and Remington's (1992) sampled disc formula (eq. 3.1),
//!   kept to measure against (design notes, "Form factors").
//! * [`hemicube`]: hemicube form factors (radiosity lecture notes, Immel, Cohen and Greenberg 1986): exact delta form factors
//!   and a rasterised item buffer with depth, for gathering and shooting.
//! * [`sampling`]: a small deterministic PRNG whose streams do not depend on the
//!   thread count, and stratified, jittered points on a convex polygon (Remington 1992, §6.2).
//! * [`polygon`]: clipping against a plane, triangulation, ray/triangle tests.
//! * [`visibility`]: [`visibility::Occluder`], an any-hit BVH over the input
//!   polygons for segment visibility, with a shared-origin packet path.
//!
//! Everything works in f64 at the interface; the BVH stores its triangles in f32
//! relative to the scene's own centre, with a scale-aware epsilon
//! ([`visibility::Occluder::scene_epsilon`]) that absorbs the f32 rounding.

mod bvh;
pub mod formfactor;
pub mod hemicube;
pub mod polygon;
pub mod sampling;
pub mod solid_angle;
pub mod visibility;
