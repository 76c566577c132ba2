//! The program's one error type, its exit codes and its rendering (the bottom layer: every room may use it,
//! and it uses no room but `util`).
//!
//! Every failure a command can report is an [`Error`] with a stable code (`pedsynth::<area>::<what>`). Each code
//! belongs to one [`Kind`], which decides the exit code: **2** for bad input (a spec, a plan, a map, an
//! argument, a dataset), **1** for the environment (reading or writing files, disk, permissions).
//! [`codes::CODES`] lists every code with its kind and meaning. A stage with an error type of its own (a spec's
//! problems, a road network that cannot be loaded) implements [`Report`], so this module needs none of them.

pub mod codes;

pub use codes::{CODES, CodeInfo, code, code_info, codes_markdown};

/// What kind of failure an error is; decides the exit code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Bad input: a spec, a plan, a map, an argument or a dataset (exit 2).
    Input,
    /// The environment failed (reading or writing files, disk, permissions), or an internal failure (exit 1).
    Environment,
}

impl Kind {
    /// The process exit code of this kind.
    pub fn exit_code(self) -> i32 {
        match self {
            Kind::Input => exit::INVALID,
            Kind::Environment => exit::FAILURE,
        }
    }
}

/// The JSON text of `value` (pretty-printed with `pretty`). A failure is an error, never an empty text.
pub fn to_json<T: serde::Serialize + ?Sized>(value: &T, pretty: bool) -> Result<String, Error> {
    let result = if pretty {
        serde_json::to_string_pretty(value)
    } else {
        serde_json::to_string(value)
    };
    result.map_err(|e| Error::new(code::INTERNAL_SERIALIZE, format!("cannot serialise to JSON: {e}")))
}

/// An error any command can report.
#[derive(Debug)]
pub enum Error {
    /// A stage's own report: a spec with problems (rendered with the lines of the spec they point at), a road
    /// network that cannot be loaded.
    Report(Box<dyn Report>),
    /// Any other failure.
    Other {
        /// Stable code (registered in [`CODES`]).
        code: &'static str,
        /// What went wrong, naming the file or value concerned.
        message: String,
        /// How to fix it.
        help: Option<String>,
    },
    /// Several errors (e.g. `validate` of several specs), reported together.
    Many(Vec<Error>),
}

impl Error {
    /// An error with a registered `code` and a message.
    pub fn new(code: &'static str, message: impl Into<String>) -> Error {
        Error::Other {
            code,
            message: message.into(),
            help: None,
        }
    }

    /// The same error with a hint on how to fix it.
    pub fn help(self, help: impl Into<String>) -> Error {
        match self {
            Error::Other { code, message, .. } => Error::Other {
                code,
                message,
                help: Some(help.into()),
            },
            other => other,
        }
    }

    /// A failure to read `path`.
    pub fn read(path: &std::path::Path, err: impl std::fmt::Display) -> Error {
        Error::new(code::IO_READ, format!("cannot read {}: {err}", path.display()))
    }

    /// A failure to write `path`.
    pub fn write(path: &std::path::Path, err: impl std::fmt::Display) -> Error {
        Error::new(code::IO_WRITE, format!("cannot write {}: {err}", path.display()))
    }

    /// A failure to write to standard output or standard error.
    pub fn output(err: impl std::fmt::Display) -> Error {
        Error::new(code::IO_OUTPUT, format!("cannot write the output: {err}"))
    }

    /// The error's code (the first one's, for several).
    pub fn code(&self) -> &'static str {
        match self {
            Error::Report(e) => e.code(),
            Error::Other { code, .. } => code,
            Error::Many(errors) => errors.first().map_or(code::IO_OUTPUT, Error::code),
        }
    }

    /// The error's kind: the environment's if any part is an environment failure, else the input's.
    pub fn kind(&self) -> Kind {
        match self {
            Error::Many(errors) if errors.iter().any(|e| e.kind() == Kind::Environment) => Kind::Environment,
            Error::Many(_) => Kind::Input,
            other => code_info(other.code()).map_or(Kind::Environment, |c| c.kind),
        }
    }

    /// The error rendered for a terminal (no colour, fixed width), ending with a newline.
    pub fn render(&self) -> String {
        match self {
            Error::Report(e) => e.render(),
            Error::Other { code, message, help } => {
                let mut out = format!("{code}\n\n  × {message}\n");
                if let Some(help) = help {
                    out.push_str(&format!("  help: {help}\n"));
                }
                out
            }
            Error::Many(errors) => errors.iter().map(Error::render).collect(),
        }
    }
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Report(e) => f.write_str(&e.summary()),
            Error::Other { message, .. } => f.write_str(message),
            Error::Many(errors) => {
                for (i, e) in errors.iter().enumerate() {
                    if i > 0 {
                        f.write_str("; ")?;
                    }
                    write!(f, "{e}")?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for Error {}

/// An error type of a stage that reports itself: its code, its one-line summary and its full rendering.
pub trait Report: std::fmt::Debug + Send + Sync + 'static {
    /// The registered code of the report (the first problem's, for several).
    fn code(&self) -> &'static str;
    /// One line: what failed.
    fn summary(&self) -> String;
    /// The report rendered for a terminal (no colour, [`DIAGNOSTIC_WIDTH`] columns), ending with a newline.
    fn render(&self) -> String;
}

impl Error {
    /// A stage's report as an error.
    pub fn report(report: impl Report) -> Error {
        Error::Report(Box::new(report))
    }
}

/// Process exit codes.
pub mod exit {
    /// Success.
    pub const OK: i32 = 0;
    /// A failure that is not the input's fault (I/O, disk, permissions, internal).
    pub const FAILURE: i32 = 1;
    /// Invalid input: a spec, plan, map, argument or dataset.
    pub const INVALID: i32 = 2;
}

/// Width diagnostics are rendered at.
pub const DIAGNOSTIC_WIDTH: usize = 100;

/// Renders any diagnostic without colour at the fixed width.
pub fn render_diagnostic(diagnostic: &dyn miette::Diagnostic) -> String {
    let handler = miette::GraphicalReportHandler::new_themed(miette::GraphicalTheme::unicode_nocolor())
        .with_width(DIAGNOSTIC_WIDTH)
        .with_links(false);
    let mut out = String::new();
    if handler.render_report(&mut out, diagnostic).is_err() {
        // The handler failed half-way (it writes to a String, so only a formatting bug can do this): fall back
        // to the plain message rather than lose the error.
        out = format!("{diagnostic}\n");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_and_well_formed() {
        let mut seen = std::collections::BTreeSet::new();
        for c in CODES {
            assert!(seen.insert(c.code), "{} listed twice", c.code);
            let parts: Vec<&str> = c.code.split("::").collect();
            assert!(
                parts.len() == 3
                    && parts[0] == "pedsynth"
                    && parts[1..].iter().all(|p| !p.is_empty()
                        && p.chars()
                            .all(|ch| ch.is_ascii_lowercase() || ch == '_' || ch.is_ascii_digit())),
                "{}",
                c.code
            );
        }
    }

    #[test]
    fn the_kind_decides_the_exit_code() {
        assert_eq!(Error::new(code::IO_WRITE, "disk full").kind().exit_code(), 1);
        assert_eq!(Error::new(code::PLAN_INVALID, "not a plan").kind().exit_code(), 2);
        let many = Error::Many(vec![
            Error::new(code::PLAN_INVALID, "a"),
            Error::new(code::IO_READ, "b"),
        ]);
        assert_eq!(many.kind(), Kind::Environment);
    }
}
