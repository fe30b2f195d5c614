//! Radiance's ambient file format (under construction)
