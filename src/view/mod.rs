//! The point of view, without a GPU: the orbit camera and what lies under the cursor.

pub mod camera;
pub mod frame_view;
pub mod pick;
