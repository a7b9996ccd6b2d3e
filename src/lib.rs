pub mod accel;
pub mod error;
pub mod estimators;
pub mod image;
pub mod progress;
pub mod render;
pub mod sampling;
pub mod scene;
