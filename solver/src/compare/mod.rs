//! `solver compare`'s measurements: how far a test image (a `runtime screenshot`,
//! say) is from a reference image (the path tracer's ground truth). Pure: the
//! readers take a path and return an image, everything else is arithmetic.
//!
//! * [`image`]: the image type and luminance;
//! * [`read`] and [`npy`]: OpenEXR and NumPy `.npy` readers, with the reference
//!   channels (`se.*`, `material_id`, `object_id`) where present;
//! * [`metrics`]: means, relative RMSE, MARE, maximum error, the per-material and
//!   per-object breakdown and the reference's own noise;
//! * [`edge_band`]: the error on the reference's sharp edges apart from the rest;
//! * [`flip`]: LDR-FLIP and HDR-FLIP;
//! * [`heatmap`]: the signed relative error as a diverging colour map.

pub mod edge_band;
pub mod flip;
pub mod heatmap;
pub mod image;
pub mod metrics;
pub mod npy;
pub mod read;
