pub mod error;
pub mod scene;
