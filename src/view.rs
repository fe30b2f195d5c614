//! view (under construction)
