//! Stereo walkthrough runtime.
