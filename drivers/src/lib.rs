//! Device drivers (Flock of Birds, CyberGlove, SpaceMouse, OSC streams): not implemented yet;
//! the crate exists so the workspace has its final shape.
