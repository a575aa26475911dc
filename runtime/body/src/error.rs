//! The errors of the body model: names a skeleton does not have, values out of range.

use thiserror::Error;

/// Everything that can go wrong when building a body or running its algorithms on outside input.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A joint name that the skeleton does not have.
    #[error("unknown joint `{name}` in skeleton `{skeleton}`{hint}")]
    UnknownJoint {
        /// The name asked for.
        name: String,
        /// The skeleton's name.
        skeleton: String,
        /// The nearest name the skeleton has (see [`did_you_mean`]), or nothing.
        hint: String,
    },
    /// A DOF name that the skeleton does not have.
    #[error("unknown DOF `{name}` in skeleton `{skeleton}`{hint}")]
    UnknownDof {
        /// The name asked for.
        name: String,
        /// The skeleton's name.
        skeleton: String,
        /// The nearest name the skeleton has (see [`did_you_mean`]), or nothing.
        hint: String,
    },
    /// A scope name (or scope expression term) that means nothing for the skeleton.
    #[error("unknown scope `{name}` in skeleton `{skeleton}` (known scopes: {known})")]
    UnknownScope {
        /// The name or term asked for.
        name: String,
        /// The skeleton's name.
        skeleton: String,
        /// The skeleton's scope names, comma-separated.
        known: String,
    },
    /// A body template name that does not exist.
    #[error("unknown body template `{name}` (known templates: {known})")]
    UnknownTemplate {
        /// The name asked for.
        name: String,
        /// The template names, comma-separated.
        known: String,
    },
    /// A name used twice where names must be unique.
    #[error("{what} `{name}` already exists")]
    Duplicate {
        /// What kind of thing is named (joint, DOF, scope, …).
        what: &'static str,
        /// The name used twice.
        name: String,
    },
    /// A numeric parameter outside its valid range.
    #[error("invalid {what}: {} ({expected})", readable(*.value))]
    InvalidValue {
        /// The parameter.
        what: String,
        /// The value given.
        value: f64,
        /// The range it must be in.
        expected: String,
    },
    /// A simulation step that could not be taken: a speed above the limit, a value that
    /// is not finite, or a DOF that lost all its inertia. The state is the one at the
    /// failed step's start.
    #[error("dynamics: the simulation diverged at t = {time:.3} s: {what}")]
    Diverged {
        /// The simulated time at the failed step's start (s).
        time: f64,
        /// What went wrong.
        what: String,
    },
    /// Forward dynamics at a posture with no unique acceleration.
    #[error("dynamics: singular configuration (a free root at pitch ±90° has no unique Euler-angle acceleration)")]
    SingularConfiguration,
    /// Anything else a caller asked for that cannot be done, with the reason.
    #[error("{0}")]
    Invalid(String),
}

/// A number as a message shows it: as written for everyday sizes, in exponent form for
/// huge and tiny ones (1e308 printed 309 digits).
fn readable(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e9).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

impl Error {
    /// Shorthand for [`Error::InvalidValue`].
    pub fn invalid_value(what: impl Into<String>, value: f64, expected: impl Into<String>) -> Self {
        Error::InvalidValue {
            what: what.into(),
            value,
            expected: expected.into(),
        }
    }
}

/// The body model's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// "; did you mean `NAME`?" for the name of `known` nearest to `name` by edits (inserted,
/// deleted or changed characters), when it is near enough to be a slip (at most a third
/// of the name's length); else nothing.
pub fn did_you_mean<'a>(name: &str, known: impl IntoIterator<Item = &'a str>) -> String {
    let limit = (name.chars().count() / 3).max(1);
    known
        .into_iter()
        .map(|k| (edits(name, k), k))
        .filter(|&(d, _)| d <= limit)
        .min()
        .map(|(_, k)| format!("; did you mean `{k}`?"))
        .unwrap_or_default()
}

/// The edit (Levenshtein) distance between `a` and `b`.
fn edits(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diagonal + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slip_of_a_name_gets_the_nearest_one_and_a_different_name_none() {
        let known = ["r_shoulder_twist", "r_shoulder_flexion", "r_elbow_flexion"];
        assert_eq!(
            did_you_mean("r_shoulder_twisting", known),
            "; did you mean `r_shoulder_twist`?"
        );
        assert_eq!(
            did_you_mean("r_elbow_flexon", known),
            "; did you mean `r_elbow_flexion`?"
        );
        assert_eq!(did_you_mean("pelvis_tilt", known), "");
        assert_eq!(edits("kitten", "sitting"), 3);
        assert_eq!(edits("", "abc"), 3);
    }
}
