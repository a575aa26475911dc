//! Glove gestures (thesis 6.4.1): hand postures recognized as commands, trained from
//! recorded examples, fired on a change of posture.
//!
//! Thesis 6.4.1: a neutral gesture plus command gestures; "we use the change of hand posture
//! instead of the posture itself to trigger a command to avoid redundant reset and
//! calibration". A posture is classified by the nearest trained mean (Euclidean distance
//! over raw sensor values); a new gesture fires only once it has held for `hold` samples,
//! so the transition through intermediate postures does not fire spurious commands.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Gesture examples that cannot be trained, or a gesture file that cannot be read or
/// written.
#[derive(Debug, thiserror::Error)]
pub enum GestureError {
    /// No gesture at all.
    #[error("no gesture examples")]
    NoExamples,
    /// Gestures, but no posture in any of them.
    #[error("gesture examples are empty")]
    EmptyExamples,
    /// A gesture without a posture.
    #[error("gesture '{0}' has no example")]
    NoExample(String),
    /// A posture with another sensor count than the first.
    #[error("gesture '{gesture}': an example has {got} sensors, expected {expected}")]
    SensorCount {
        /// The gesture.
        gesture: String,
        /// Its example's sensors.
        got: usize,
        /// The first example's sensors.
        expected: usize,
    },
    /// A gesture named twice.
    #[error("gesture '{0}' is given twice")]
    Twice(String),
    /// The set could not be encoded as JSON.
    #[error("{0}")]
    Encode(#[source] serde_json::Error),
    /// The file could not be written.
    #[error("writing {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// The file could not be read.
    #[error("reading {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a gesture set's JSON.
    #[error("{}: not a gesture set: {source}", path.display())]
    NotAGestureSet {
        /// The file.
        path: PathBuf,
        /// What the JSON parser said (with line and column).
        #[source]
        source: serde_json::Error,
    },
    /// The file's lists disagree in length.
    #[error("{}: {names} names for {means} means", path.display())]
    Lists {
        /// The file.
        path: PathBuf,
        /// Gesture names.
        names: usize,
        /// Means.
        means: usize,
    },
}

/// A trained set of gestures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GestureSet {
    /// Gesture names, one of them usually `neutral`.
    pub names: Vec<String>,
    /// Mean raw posture per gesture.
    pub means: Vec<Vec<f64>>,
    /// A posture farther than this (raw units, Euclidean) from every mean is unrecognized.
    pub max_distance: f64,
    /// Consecutive samples a new gesture must hold before it fires.
    pub hold: usize,
}

impl GestureSet {
    /// Trains from examples: for each gesture, one or more raw postures. Every example must
    /// have the same sensor count; the recognition radius is twice the largest spread of
    /// any gesture's examples around its mean, and at least 20 raw units.
    pub fn train(examples: &[(String, Vec<Vec<u8>>)]) -> Result<GestureSet, GestureError> {
        if examples.is_empty() {
            return Err(GestureError::NoExamples);
        }
        let n = examples
            .iter()
            .flat_map(|(_, v)| v.first())
            .map(|v| v.len())
            .next()
            .ok_or(GestureError::EmptyExamples)?;
        let mut names = Vec::new();
        let mut means = Vec::new();
        let mut spread: f64 = 0.0;
        for (name, postures) in examples {
            if postures.is_empty() {
                return Err(GestureError::NoExample(name.clone()));
            }
            if let Some(bad) = postures.iter().find(|p| p.len() != n) {
                return Err(GestureError::SensorCount {
                    gesture: name.clone(),
                    got: bad.len(),
                    expected: n,
                });
            }
            if names.contains(name) {
                return Err(GestureError::Twice(name.clone()));
            }
            let mut mean = vec![0.0; n];
            for p in postures {
                for (m, &v) in mean.iter_mut().zip(p) {
                    *m += f64::from(v);
                }
            }
            mean.iter_mut().for_each(|m| *m /= postures.len() as f64);
            for p in postures {
                spread = spread.max(distance_raw(&mean, p));
            }
            names.push(name.clone());
            means.push(mean);
        }
        Ok(GestureSet {
            names,
            means,
            max_distance: (2.0 * spread).max(20.0),
            hold: 3,
        })
    }

    /// The nearest gesture within the radius, or `None`.
    pub fn classify(&self, raw: &[u8]) -> Option<usize> {
        let (best, d) = self
            .means
            .iter()
            .enumerate()
            .map(|(i, m)| (i, distance_raw(m, raw)))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        (d <= self.max_distance).then_some(best)
    }

    /// Saves as JSON.
    pub fn save(&self, path: &Path) -> Result<(), GestureError> {
        let text = serde_json::to_string_pretty(self).map_err(GestureError::Encode)?;
        std::fs::write(path, text).map_err(|source| GestureError::Write {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Loads a JSON gesture set.
    pub fn load(path: &Path) -> Result<GestureSet, GestureError> {
        let text = std::fs::read_to_string(path).map_err(|source| GestureError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let g: GestureSet =
            serde_json::from_str(&text).map_err(|source| GestureError::NotAGestureSet {
                path: path.to_path_buf(),
                source,
            })?;
        if g.names.len() != g.means.len() {
            return Err(GestureError::Lists {
                path: path.to_path_buf(),
                names: g.names.len(),
                means: g.means.len(),
            });
        }
        Ok(g)
    }
}

fn distance_raw(mean: &[f64], raw: &[u8]) -> f64 {
    if mean.len() != raw.len() {
        return f64::INFINITY;
    }
    mean.iter()
        .zip(raw)
        .map(|(m, &r)| (m - f64::from(r)).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Turns a stream of postures into gesture changes.
#[derive(Clone, Debug)]
pub struct GestureTracker {
    set: GestureSet,
    current: Option<usize>,
    candidate: Option<usize>,
    count: usize,
}

impl GestureTracker {
    /// A tracker with no gesture yet.
    pub fn new(set: GestureSet) -> GestureTracker {
        GestureTracker {
            set,
            current: None,
            candidate: None,
            count: 0,
        }
    }

    /// The gesture held now.
    pub fn current(&self) -> Option<&str> {
        self.current.map(|i| self.set.names[i].as_str())
    }

    /// Feeds one posture; returns `(new, previous)` names when the held gesture changes.
    pub fn feed(&mut self, raw: &[u8]) -> Option<(String, Option<String>)> {
        let g = self.set.classify(raw);
        if g == self.current {
            self.candidate = None;
            self.count = 0;
            return None;
        }
        if g != self.candidate {
            self.candidate = g;
            self.count = 0;
        }
        self.count += 1;
        let g = g?;
        if self.count < self.set.hold {
            return None;
        }
        let previous = self.current().map(String::from);
        self.current = Some(g);
        self.candidate = None;
        self.count = 0;
        Some((self.set.names[g].clone(), previous))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn examples() -> Vec<(String, Vec<Vec<u8>>)> {
        let p = |v: u8| vec![v; 18];
        let mut fist = p(230);
        fist[0] = 120;
        let mut point = p(230);
        point[4..7].copy_from_slice(&[20, 20, 20]);
        let mut thumbs_up = p(230);
        thumbs_up[0..4].copy_from_slice(&[20, 20, 20, 20]);
        let mut spread = p(20);
        for i in [10, 14, 17] {
            spread[i] = 200;
        }
        vec![
            ("neutral".into(), vec![p(60), p(70)]),
            (
                "fist".into(),
                vec![fist.clone(), fist.iter().map(|v| v - 5).collect()],
            ),
            ("point".into(), vec![point]),
            ("thumbs_up".into(), vec![thumbs_up]),
            ("spread".into(), vec![spread]),
        ]
    }

    #[test]
    fn classifies_each_trained_posture() {
        let ex = examples();
        let set = GestureSet::train(&ex).unwrap();
        for (i, (_, postures)) in ex.iter().enumerate() {
            assert_eq!(set.classify(&postures[0]), Some(i));
        }
        // Near a trained posture: that gesture; far from everything: unrecognized.
        let near_fist: Vec<u8> = ex[1].1[0].iter().map(|v| v + 3).collect();
        assert_eq!(
            set.classify(&near_fist).map(|i| set.names[i].as_str()),
            Some("fist")
        );
        let mut odd = vec![128u8; 18];
        odd[0] = 1;
        odd[17] = 255;
        assert_eq!(set.classify(&odd), None);
        assert!(
            set.classify(&[1, 2, 3]).is_none(),
            "wrong sensor count is unrecognized"
        );
    }

    #[test]
    fn fires_once_on_a_change_after_holding() {
        let ex = examples();
        let set = GestureSet::train(&ex).unwrap();
        let mut t = GestureTracker::new(set);
        let neutral = &ex[0].1[0];
        let fist = &ex[1].1[0];
        let fired: Vec<_> = [
            neutral, neutral, neutral, neutral, fist, neutral, fist, fist, fist, fist, fist,
        ]
        .iter()
        .filter_map(|p| t.feed(p))
        .collect();
        assert_eq!(
            fired,
            vec![
                ("neutral".to_string(), None),
                ("fist".to_string(), Some("neutral".to_string()))
            ]
        );
        assert_eq!(t.current(), Some("fist"));
    }

    #[test]
    fn bad_training_sets_are_errors() {
        assert!(GestureSet::train(&[]).is_err());
        let e = GestureSet::train(&[
            ("a".into(), vec![vec![1; 18]]),
            ("b".into(), vec![vec![1; 22]]),
        ])
        .unwrap_err()
        .to_string();
        assert!(e.contains("'b'") && e.contains("22"), "{e}");
        let e = GestureSet::train(&[
            ("a".into(), vec![vec![1; 18]]),
            ("a".into(), vec![vec![2; 18]]),
        ])
        .unwrap_err()
        .to_string();
        assert!(e.contains("twice"));
    }
}
