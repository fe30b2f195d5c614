//! image (under construction)
