//! Tessera's ambient log (under construction)
