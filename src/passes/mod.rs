//! Passes shared by techniques: each owns its pipelines and records itself
//! through `FrameRecorder::pass`.

pub mod tonemap;
