//! The files a scene's modifiers read (data files, pictures, fonts), found along the
//! RAYPATH and read once per scene.
//!
//! Radiance looks a relative name up in each RAYPATH directory in turn (default `.`, the
//! current directory, *not* the directory of the scene file that names it); an absolute name
//! is used as is. Each file is read once per scene, keyed by the path it resolved to, and
//! shared (`Arc`) by every primitive that names it; a file that fails to load fails every
//! primitive that names it with the same message.

use super::data::DataArray;
use super::font::Font;
use super::func::SceneFunctions;
use super::picdata::PictData;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

type Cache<T> = Mutex<HashMap<PathBuf, Result<Arc<T>, String>>>;

/// The RAYPATH and the files read so far for one scene.
#[derive(Default)]
pub struct SceneFiles {
    raypath: Vec<PathBuf>,
    /// Every file found so far: (name as given, path), first finds only.
    used: Mutex<Vec<(String, PathBuf)>>,
    functions: SceneFunctions,
    data: Cache<DataArray>,
    pictures: Cache<PictData>,
    fonts: Cache<Font>,
}

impl std::fmt::Debug for SceneFiles {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneFiles")
            .field("raypath", &self.raypath)
            .finish_non_exhaustive()
    }
}

impl SceneFiles {
    /// Files found along `raypath` (empty: the current directory, Radiance's default).
    pub fn new(raypath: &[PathBuf]) -> SceneFiles {
        SceneFiles {
            raypath: raypath.to_vec(),
            functions: SceneFunctions::new(raypath),
            ..SceneFiles::default()
        }
    }

    /// The files the scene's primitives read, relative names only (as given, and the path
    /// found along the RAYPATH): data files, pictures, fonts, text files and function files.
    /// A batch job copies them into its directory.
    pub fn relative_inputs(&self) -> Vec<(String, PathBuf)> {
        let mut all = self.used.lock().map(|u| u.clone()).unwrap_or_default();
        for (n, p) in self.functions.file_paths() {
            if !all.iter().any(|(m, _)| *m == n) {
                all.push((n, p));
            }
        }
        all.retain(|(n, _)| Path::new(n).is_relative());
        all
    }

    /// Record a file the scene reads by name (the first record of a name wins).
    pub fn note_input(&self, name: &str, path: PathBuf) {
        let mut used = self.used.lock().unwrap_or_else(|e| e.into_inner());
        if !used.iter().any(|(n, _)| n == name) {
            used.push((name.to_string(), path));
        }
    }

    /// The scene's function language state (function files found along the RAYPATH).
    pub fn functions(&self) -> &SceneFunctions {
        &self.functions
    }

    /// The RAYPATH directories searched (never empty).
    pub fn raypath(&self) -> Vec<PathBuf> {
        if self.raypath.is_empty() {
            vec![PathBuf::from(".")]
        } else {
            self.raypath.clone()
        }
    }

    /// The file `name` resolves to: an absolute name as is, a relative one in the first
    /// RAYPATH directory that holds it.
    pub fn find(&self, name: &str) -> Result<PathBuf, String> {
        let p = Path::new(name);
        if name.is_empty() {
            return Err("empty file name".into());
        }
        if p.is_absolute() {
            return if p.is_file() {
                Ok(p.to_path_buf())
            } else {
                Err(format!("cannot find file '{name}'"))
            };
        }
        let dirs = self.raypath();
        let found = dirs.iter().map(|d| d.join(p)).find(|c| c.is_file());
        if let Some(f) = &found {
            let mut used = self.used.lock().unwrap_or_else(|e| e.into_inner());
            if !used.iter().any(|(n, _)| n == name) {
                used.push((name.to_string(), f.clone()));
            }
        }
        found.ok_or_else(|| {
            let shown: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
            format!("cannot find file '{name}' on RAYPATH {}", shown.join(":"))
        })
    }

    fn cached<T>(
        &self,
        cache: &Cache<T>,
        name: &str,
        load: impl FnOnce(&Path) -> Result<T, String>,
    ) -> Result<Arc<T>, String> {
        let path = self.find(name)?;
        let mut map = cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(r) = map.get(&path) {
            return r.clone();
        }
        let r = load(&path).map(Arc::new);
        map.insert(path, r.clone());
        r
    }

    /// The data file `name` (see [`DataArray::load`]).
    pub fn data(&self, name: &str) -> Result<Arc<DataArray>, String> {
        self.cached(&self.data, name, DataArray::load)
    }

    /// The picture `name` as 2-D data (see [`PictData::load`]).
    pub fn picture(&self, name: &str) -> Result<Arc<PictData>, String> {
        self.cached(&self.pictures, name, PictData::load)
    }

    /// The font `name` (see [`Font::load`]).
    pub fn font(&self, name: &str) -> Result<Arc<Font>, String> {
        self.cached(&self.fonts, name, Font::load)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_are_found_along_the_raypath_and_read_once() {
        let a = tempfile::tempdir().unwrap();
        let b = tempfile::tempdir().unwrap();
        std::fs::write(b.path().join("d.dat"), "1\n0 1 2\n3 4\n").unwrap();
        let files = SceneFiles::new(&[a.path().to_path_buf(), b.path().to_path_buf()]);
        let d1 = files.data("d.dat").unwrap();
        assert_eq!(d1.interp(&[0.5]), 3.5);
        // A second read gives the same array even after the file changed.
        std::fs::write(b.path().join("d.dat"), "1\n0 1 2\n30 40\n").unwrap();
        let d2 = files.data("d.dat").unwrap();
        assert!(Arc::ptr_eq(&d1, &d2));
        // The first directory wins.
        std::fs::write(a.path().join("e.dat"), "1\n0 1 2\n1 1\n").unwrap();
        std::fs::write(b.path().join("e.dat"), "1\n0 1 2\n2 2\n").unwrap();
        assert_eq!(files.data("e.dat").unwrap().interp(&[0.0]), 1.0);
        let e = files.data("missing.dat").unwrap_err();
        assert!(
            e.contains("cannot find file 'missing.dat' on RAYPATH"),
            "{e}"
        );
        // Absolute names are used as is.
        let abs = b.path().join("e.dat");
        assert_eq!(
            files.data(abs.to_str().unwrap()).unwrap().interp(&[0.0]),
            2.0
        );
        // Errors are cached and repeated.
        std::fs::write(a.path().join("bad.dat"), "1\n0 1 2\n3 x\n").unwrap();
        let e1 = files.data("bad.dat").unwrap_err();
        let e2 = files.data("bad.dat").unwrap_err();
        assert_eq!(e1, e2);
    }
}
