//! The batch toolkit's job directory protocol (`tplan`, `tpiece`, `tmerge`, `tassemble`,
//! `tstat`): see `docs/batch.md`.

pub mod plan;
