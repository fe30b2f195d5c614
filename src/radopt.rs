//! radopt (under construction)
