//! Spec diagnostics: stable codes, spans into the spec or a `--set` override, "did you mean" hints, and
//! deterministic rendering (no colour, fixed width) for terminals and golden tests.

use std::fmt;
use std::sync::Arc;

use miette::{Diagnostic, GraphicalReportHandler, GraphicalTheme, LabeledSpan, NamedSource, SourceCode};

use super::tree::Span;

/// Stable diagnostic codes of the spec language (registered with every other code in [`crate::error::codes`]).
pub use crate::error::codes::spec as code;

/// One problem in a spec, before it is attached to its source text.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// Stable code, one of [`code`].
    pub code: &'static str,
    /// What is wrong.
    pub message: String,
    /// The primary label: where, and a short note.
    pub label: Option<(Span, String)>,
    /// Further labels in the same source.
    pub secondary: Vec<(Span, String)>,
    /// How to fix it.
    pub help: Option<String>,
}

impl Problem {
    /// A problem with a message only.
    pub fn new(code: &'static str, message: impl Into<String>) -> Self {
        Problem {
            code,
            message: message.into(),
            label: None,
            secondary: Vec::new(),
            help: None,
        }
    }
    /// Adds the primary label.
    pub fn at(mut self, span: Span, note: impl Into<String>) -> Self {
        self.label = Some((span, note.into()));
        self
    }
    /// Adds a secondary label.
    pub fn also(mut self, span: Span, note: impl Into<String>) -> Self {
        self.secondary.push((span, note.into()));
        self
    }
    /// Adds a help line.
    pub fn help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }
}

/// The texts spans point into: the spec file (id 0) and each `--set` override (id n ≥ 1).
#[derive(Clone, Debug, Default)]
pub struct Sources {
    entries: Vec<(String, Arc<String>)>,
}

impl Sources {
    /// Adds a source and returns its id.
    pub fn add(&mut self, name: impl Into<String>, text: impl Into<String>) -> usize {
        self.entries.push((name.into(), Arc::new(text.into())));
        self.entries.len() - 1
    }
    /// The name and text of a source.
    pub fn get(&self, id: usize) -> Option<(&str, &Arc<String>)> {
        self.entries.get(id).map(|(n, t)| (n.as_str(), t))
    }
}

/// A problem attached to its source: a complete miette diagnostic.
#[derive(Debug)]
pub struct SpecProblem {
    problem: Problem,
    source: Option<NamedSource<Arc<String>>>,
}

impl fmt::Display for SpecProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.problem.message)
    }
}

impl std::error::Error for SpecProblem {}

impl Diagnostic for SpecProblem {
    fn code<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        Some(Box::new(self.problem.code))
    }
    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        self.problem.help.as_ref().map(|h| Box::new(h) as Box<dyn fmt::Display>)
    }
    fn source_code(&self) -> Option<&dyn SourceCode> {
        self.source.as_ref().map(|s| s as &dyn SourceCode)
    }
    fn labels(&self) -> Option<Box<dyn Iterator<Item = LabeledSpan> + '_>> {
        self.source.as_ref()?;
        let (primary_span, primary_note) = self.problem.label.as_ref()?;
        let primary =
            LabeledSpan::new_primary_with_span(Some(primary_note.clone()), (primary_span.offset, primary_span.len));
        let secondary = self
            .problem
            .secondary
            .iter()
            .filter(|(span, _)| span.source == primary_span.source)
            .map(|(span, note)| LabeledSpan::new_with_span(Some(note.clone()), (span.offset, span.len)));
        Some(Box::new(std::iter::once(primary).chain(secondary)))
    }
}

/// Every problem found in one spec: the error `load` returns.
#[derive(Debug)]
pub struct SpecErrors {
    /// The spec's display name (as given on the command line).
    pub name: String,
    /// The problems, in document order.
    pub problems: Vec<SpecProblem>,
}

impl SpecErrors {
    /// Attaches problems to their sources; problems are sorted by position for a stable report.
    pub fn new(name: impl Into<String>, mut problems: Vec<Problem>, sources: &Sources) -> Self {
        problems.sort_by_key(|p| {
            p.label
                .as_ref()
                .map(|(s, _)| (s.source, s.offset))
                .unwrap_or((usize::MAX, 0))
        });
        problems.dedup();
        let problems = problems
            .into_iter()
            .map(|problem| {
                let source = problem
                    .label
                    .as_ref()
                    .and_then(|(span, _)| sources.get(span.source))
                    .map(|(name, text)| NamedSource::new(name, Arc::clone(text)));
                SpecProblem { problem, source }
            })
            .collect();
        SpecErrors {
            name: name.into(),
            problems,
        }
    }

    /// The codes of the problems, in report order.
    pub fn codes(&self) -> Vec<&'static str> {
        self.problems.iter().map(|p| p.problem.code).collect()
    }

    /// The problems without their sources.
    pub fn problems(&self) -> impl Iterator<Item = &Problem> {
        self.problems.iter().map(|p| &p.problem)
    }

    /// Renders every problem without colour at a fixed width: deterministic, for golden tests and for
    /// terminals that are not TTYs.
    pub fn render_plain(&self, width: usize) -> String {
        let handler = GraphicalReportHandler::new_themed(GraphicalTheme::unicode_nocolor())
            .with_width(width)
            .with_links(false);
        let mut out = String::new();
        out.push_str(&self.to_string());
        out.push('\n');
        for problem in &self.problems {
            out.push('\n');
            if handler.render_report(&mut out, problem).is_err() {
                // Rendering into a String fails only on a formatting bug: keep the message rather than lose it.
                out.push_str(&format!("{}: {}\n", problem.problem.code, problem.problem.message));
            }
        }
        out
    }
}

impl fmt::Display for SpecErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.problems.len() {
            1 => write!(f, "{}: 1 problem", self.name),
            n => write!(f, "{}: {n} problems", self.name),
        }
    }
}

impl std::error::Error for SpecErrors {}

impl crate::error::Report for SpecErrors {
    fn code(&self) -> &'static str {
        self.codes().first().copied().unwrap_or(code::IO)
    }

    fn summary(&self) -> String {
        format!("{} problem(s) in spec {}", self.problems.len(), self.name)
    }

    fn render(&self) -> String {
        self.render_plain(crate::error::DIAGNOSTIC_WIDTH)
    }
}

impl From<SpecErrors> for crate::error::Error {
    fn from(e: SpecErrors) -> Self {
        crate::error::Error::report(e)
    }
}

impl Diagnostic for SpecErrors {
    fn related<'a>(&'a self) -> Option<Box<dyn Iterator<Item = &'a dyn Diagnostic> + 'a>> {
        Some(Box::new(self.problems.iter().map(|p| p as &dyn Diagnostic)))
    }
}

/// The closest candidate to `word`, if one is close enough to be a plausible typo.
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let lower = word.to_ascii_lowercase();
    candidates
        .into_iter()
        .map(|c| (strsim::jaro_winkler(&lower, c), c))
        .filter(|(score, _)| *score >= 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0).then_with(|| b.1.cmp(a.1)))
        .map(|(_, c)| c)
}

/// "did you mean `x`?" or a list of the valid choices when nothing is close.
pub fn suggestion(word: &str, candidates: &[&str]) -> String {
    match did_you_mean(word, candidates.iter().copied()) {
        Some(c) => format!("did you mean `{c}`?"),
        None if candidates.len() <= 12 => {
            let list: Vec<String> = candidates.iter().map(|c| format!("`{c}`")).collect();
            format!("expected one of {}", list.join(", "))
        }
        None => format!("expected one of {} names (see `pedsynth schema`)", candidates.len()),
    }
}
