//! light (under construction)
