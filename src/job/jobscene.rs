//! A worker's scene: the job's scene image mapped when it is sound (docs/batch.md, "One
//! copy of the scene per node"), else the flattened scene read and built and a new image
//! written; checked against the manifest's fingerprint; the render session started with
//! the job's shared ambient store.

use anyhow::{anyhow, bail, Result};

use super::manifest::Manifest;
use super::share::open_share;
use super::JobDir;
use crate::scene::image::{self, Rest, SceneImage};
use crate::scene::ReadOptions;
use crate::session::store::FlushPolicy;
use crate::session::{SceneSource, Session};

/// Read the job's flattened scene, refuse it if the scene or the manifest's parameters no
/// longer give the manifest's fingerprint, and start the render session (with ambient
/// sharing when the values are cached).
/// How a worker starts its scene: `--amb-flush`, whether it maps the scene image (not
/// with `--no-scene-image`) and whether it says so when it cannot.
pub(super) struct SceneStart {
    pub(super) amb_flush: FlushPolicy,
    pub(super) scene_image: bool,
    pub(super) verbose: bool,
}

pub(super) fn start_session(
    job: &JobDir,
    m: &Manifest,
    owner: &str,
    wo: &SceneStart,
) -> Result<Session> {
    let scene_path = job.file(&m.scene_file);
    crate::safefile::check_plain_tree(&scene_path)?;
    crate::safefile::check_plain_tree(&job.root().join(super::manifest::INPUTS_DIR))?;
    // The files the planner copied (function files, data files, pictures, fonts), the job
    // directory (the flattened scene names no other scene file), then the RAYPATH.
    let mut raypath = vec![
        job.root().join(super::manifest::INPUTS_DIR),
        job.root().to_path_buf(),
    ];
    raypath.extend(ReadOptions::from_env().raypath);
    let ro = ReadOptions {
        allow_commands: false,
        raypath,
        // The flattened scene holds what the planner counted (its limit was applied there);
        // an edited scene is refused by its fingerprint.
        max_primitives: m
            .primitives
            .max(crate::scene::reader::DEFAULT_MAX_PRIMITIVES),
        ..ReadOptions::default()
    };
    // The tile loops render on threads of their own: the session's pool is not used. With
    // a sound scene image (JOB/scene.img) the geometry (the top level's and every set's) is
    // mapped from it and the other primitives come from it too: no scene or instanced file
    // is read, no surface parsed. Without one, or with a damaged or foreign one, the scene
    // is read from JOB/scene.rad and built, and a new image is written.
    let plain = || -> Result<(Session, Rest)> {
        let source = SceneSource::read(&[scene_path.display().to_string()], &ro, &m.params)?;
        let mut rest = Rest::of(&source.prims, source.fingerprint);
        rest.scene_file = Some(super::file_crc(&scene_path)?);
        Ok((Session::start(m.params.clone(), source, Some(1))?, rest))
    };
    let image_path = job.file(super::manifest::SCENE_IMAGE);
    let image = match std::fs::symlink_metadata(&image_path) {
        _ if !wo.scene_image => Err(None),
        Err(_) => Err(Some("there is none".to_string())),
        Ok(_) => SceneImage::open(&image_path, &m.fingerprint_bytes()).map_err(Some),
    };
    let image_scene = image.as_ref().ok().and_then(|i| i.scene_file());
    let mapped = match image {
        Ok(image) => match image.rest(&ro) {
            Ok((prims, fingerprint)) => {
                let source = SceneSource {
                    prims,
                    fingerprint,
                    raypath: ro.raypath.clone(),
                    allow_commands: false,
                };
                Session::start_with_image(m.params.clone(), source, Some(1), &image)?.map_err(Some)
            }
            Err(e) => Err(Some(format!("damaged: {e}"))),
        },
        Err(why) => Err(why),
    };
    let changed = || {
        anyhow!(
            "{}: the scene or the manifest's options changed since the job was planned; \
             plan a new job",
            scene_path.display()
        )
    };
    let (mut session, refused) = match mapped {
        Ok(_) if image_scene != Some(super::file_crc(&scene_path)?) => return Err(changed()),
        Ok(s) => (s, None),
        Err(None) => (plain()?.0, None),
        Err(Some(why)) => {
            let (s, rest) = plain()?;
            (s, Some((why, rest)))
        }
    };
    // The fingerprint covers the files the scene reads (JOB/files/), known once it is built.
    if session.fingerprint != m.fingerprint_bytes() {
        bail!(
            "{}: the scene or the manifest's options changed since the job was planned \
             (fingerprint {} instead of {}); plan a new job",
            scene_path.display(),
            super::hex32(&session.fingerprint),
            m.fingerprint
        );
    }
    if let Some((why, rest)) = refused {
        // The worker renders without an image as well: one it cannot write (a full disk,
        // a read-only job directory) is a warning, not a failure.
        let bytes = image::encode(&m.fingerprint_bytes(), &rest, &session.scene.geom);
        let wrote = super::write_file_atomic(&image_path, &bytes);
        if wo.verbose || wrote.is_err() {
            let what = match wrote {
                Ok(()) => "wrote a new one".to_string(),
                Err(e) => format!("cannot write a new one: {e}"),
            };
            eprintln!(
                "tpiece: warning: {}: not used ({why}); built the scene and {what}",
                image_path.display()
            );
        }
    }
    if session.cached_ambient().is_some() {
        let store = open_share(job, owner, &session, wo.amb_flush)?;
        session.attach_store(store);
    }
    Ok(session)
}
