//! Errors of the scene front end (lexer, reader, inline commands).

use super::primitive::Location;

/// Everything that can go wrong while reading a scene.
///
/// Every variant displays on one line as `file:line: reason`. Errors about a top-level file
/// that cannot be opened use line 0.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// Malformed scene text (bad counts, non-numbers, truncated primitives, bad quotes,
    /// bad arguments to a built-in command).
    #[error("{loc}: {reason}")]
    Syntax {
        /// Where the problem is.
        loc: Location,
        /// What is wrong.
        reason: String,
    },
    /// A scene file could not be found or read.
    #[error("{loc}: cannot read scene file '{path}': {reason}")]
    Io {
        /// Where the file was named (the file itself with line 0 for top-level files).
        loc: Location,
        /// The path as named.
        path: String,
        /// The operating-system reason.
        reason: String,
    },
    /// An octree was given where scene text is expected.
    #[error("{loc}: '{path}' looks like an octree; octrees are not read, give the .rad scene files instead")]
    Octree {
        /// Where the octree was named.
        loc: Location,
        /// The path as named.
        path: String,
    },
    /// An external inline command appeared while commands are not allowed.
    #[error("{loc}: inline command '{name}' needs --allow-commands (or TESSERA_ALLOW_COMMANDS=1){note}: !{command}")]
    CommandNotAllowed {
        /// Where the command is.
        loc: Location,
        /// The command's program name.
        name: String,
        /// The whole command line.
        command: String,
        /// Empty, or ` (why the built-in version cannot handle it)`.
        note: String,
    },
    /// An inline command could not be run or failed.
    #[error("{loc}: inline command '!{command}' failed: {reason}")]
    CommandFailed {
        /// Where the command is.
        loc: Location,
        /// The whole command line.
        command: String,
        /// Why it failed (exit status and its stderr).
        reason: String,
    },
    /// Inline commands nested too deeply (usually a file that includes itself).
    #[error("{loc}: recursion too deep ({depth} nested inline commands) expanding '!{command}'; does a file include itself?")]
    Recursion {
        /// Where the command is.
        loc: Location,
        /// The nesting depth reached.
        depth: u32,
        /// The command line.
        command: String,
    },
}

impl SceneError {
    /// A syntax error at `loc`.
    pub fn syntax(loc: Location, reason: impl Into<String>) -> SceneError {
        SceneError::Syntax {
            loc,
            reason: reason.into(),
        }
    }

    /// Where the error is.
    pub fn location(&self) -> &Location {
        match self {
            SceneError::Syntax { loc, .. }
            | SceneError::Io { loc, .. }
            | SceneError::Octree { loc, .. }
            | SceneError::CommandNotAllowed { loc, .. }
            | SceneError::CommandFailed { loc, .. }
            | SceneError::Recursion { loc, .. } => loc,
        }
    }
}
