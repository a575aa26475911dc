//! The errors of the action kinds: options refused before an action is made (each names
//! the option and what it expects), and actions that cannot be made for a body or scene.

use thiserror::Error;

/// An option that a kind's `validate()` refuses.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum OptionError {
    /// A required option is absent.
    #[error("`{option}` is required")]
    Missing {
        /// The option's name.
        option: &'static str,
    },
    /// An option's value is not one the kind accepts.
    #[error("`{option}` must be {expected}, got {got}")]
    Invalid {
        /// The option's name.
        option: &'static str,
        /// What the option accepts ("a number in [0, 1]").
        expected: String,
        /// The value given.
        got: String,
    },
    /// An option refused with an explanation of its own (its message is the reason,
    /// worded as users have always read it).
    #[error("{reason}")]
    Refused {
        /// The option's name.
        option: &'static str,
        /// Why it is refused.
        reason: String,
    },
}

impl OptionError {
    /// `option` must be `expected`, and `got` was given.
    pub fn invalid(
        option: &'static str,
        expected: impl Into<String>,
        got: impl std::fmt::Display,
    ) -> OptionError {
        OptionError::Invalid {
            option,
            expected: expected.into(),
            got: got.to_string(),
        }
    }

    /// `option` is refused because of `reason`.
    pub fn refused(option: &'static str, reason: impl Into<String>) -> OptionError {
        OptionError::Refused {
            option,
            reason: reason.into(),
        }
    }

    /// The name of the refused option.
    pub fn option(&self) -> &'static str {
        match self {
            OptionError::Missing { option }
            | OptionError::Invalid { option, .. }
            | OptionError::Refused { option, .. } => option,
        }
    }
}

#[cfg(test)]
impl OptionError {
    /// Asserts that this error refuses `option` and names it in its message.
    pub(crate) fn assert_names(&self, option: &str) {
        assert_eq!(self.option(), option, "{self}");
        assert!(self.to_string().contains(option), "{self}");
    }
}

/// The DOF of each track of `sequence` on `skeleton`, in track order. A track that names
/// no DOF of the body is refused as `option`, naming the sequence (an inline one is named
/// after the line that made it), the track and the nearest DOF name.
pub(crate) fn track_dofs(
    skeleton: &troupe_body::Skeleton,
    sequence: &troupe_motion::Sequence,
    option: &'static str,
) -> std::result::Result<Vec<usize>, OptionError> {
    sequence
        .tracks()
        .iter()
        .map(|track| {
            skeleton.dof(track.dof()).map_err(|e| {
                OptionError::refused(option, format!("sequence `{}`: {e}", sequence.name))
            })
        })
        .collect()
}

/// Why an action cannot be made.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ActionError {
    /// An option is refused.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// The body model refused (an unknown joint, DOF or scope; a solver that cannot be
    /// set up).
    #[error(transparent)]
    Body(#[from] troupe_body::Error),
    /// The scene refused (an unknown actor or object, an action that cannot start).
    #[error(transparent)]
    Scene(#[from] troupe_scene::Error),
    /// The actor cannot do the action (a body without a humanoid's legs for a walk, a
    /// performer's device-driven hand for a give), and why.
    #[error("{0}")]
    Unfit(String),
}

/// A generator whose action cannot be made for the body or the scene it meets at its
/// start fails its action with the reason.
impl From<ActionError> for troupe_scene::StartError {
    fn from(e: ActionError) -> Self {
        troupe_scene::StartError::new(e.to_string())
    }
}

/// The result of making an action.
pub type Result<T, E = ActionError> = std::result::Result<T, E>;
