pub mod error;
pub mod scene;
pub mod accel;
pub mod sampling;
pub mod estimators;
pub mod progress;
pub mod image;
pub mod render;
