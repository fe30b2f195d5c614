//! geometry (under construction)
