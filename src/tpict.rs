//! tpict (under construction)
