//! SCOPE (thesis 6.4.3): a subset of an actor's degrees of freedom, stored as a bitset.
//!
//! Scopes are the scheduler's vocabulary: two actions conflict when their scopes overlap,
//! and a generator may write only the DOFs of its action's scope.

use std::fmt;

/// The largest number of DOFs a skeleton may have (the width of a [`Scope`]).
pub const MAX_DOFS: usize = 256;
const WORDS: usize = MAX_DOFS / 64;

/// A set of DOF indices of one skeleton. Cheap to copy; set operations are a few word ops.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Scope {
    words: [u64; WORDS],
}

impl Scope {
    /// The empty scope.
    pub const EMPTY: Scope = Scope { words: [0; WORDS] };

    /// A scope holding the DOF indices in `range`.
    #[inline]
    pub fn range(range: std::ops::Range<usize>) -> Scope {
        let mut s = Scope::EMPTY;
        for i in range {
            s.insert(i);
        }
        s
    }

    /// A scope holding the given DOF indices.
    pub fn from_indices(indices: impl IntoIterator<Item = usize>) -> Scope {
        let mut s = Scope::EMPTY;
        for i in indices {
            s.insert(i);
        }
        s
    }

    /// Adds DOF `i`. Panics if `i >= MAX_DOFS` (skeletons are validated to stay below it).
    #[inline]
    pub fn insert(&mut self, i: usize) {
        assert!(i < MAX_DOFS, "DOF index {i} exceeds MAX_DOFS");
        self.words[i / 64] |= 1 << (i % 64);
    }

    /// Removes DOF `i`.
    #[inline]
    pub fn remove(&mut self, i: usize) {
        if i < MAX_DOFS {
            self.words[i / 64] &= !(1 << (i % 64));
        }
    }

    /// Whether DOF `i` is in the scope.
    #[inline]
    pub fn contains(&self, i: usize) -> bool {
        i < MAX_DOFS && self.words[i / 64] & (1 << (i % 64)) != 0
    }

    /// Whether the scope holds no DOF.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.words.iter().all(|w| *w == 0)
    }

    /// The number of DOFs in the scope.
    #[inline]
    pub fn len(&self) -> usize {
        self.words.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// The DOFs in either scope.
    #[inline]
    pub fn union(&self, other: &Scope) -> Scope {
        self.zip(other, |a, b| a | b)
    }

    /// The DOFs in both scopes.
    #[inline]
    pub fn intersection(&self, other: &Scope) -> Scope {
        self.zip(other, |a, b| a & b)
    }

    /// The DOFs of `self` that are not in `other`.
    #[inline]
    pub fn difference(&self, other: &Scope) -> Scope {
        self.zip(other, |a, b| a & !b)
    }

    /// Whether the two scopes share at least one DOF.
    #[inline]
    pub fn overlaps(&self, other: &Scope) -> bool {
        self.words
            .iter()
            .zip(other.words.iter())
            .any(|(a, b)| a & b != 0)
    }

    /// Whether every DOF of `other` is in `self`.
    #[inline]
    pub fn contains_all(&self, other: &Scope) -> bool {
        other.difference(self).is_empty()
    }

    /// The DOF indices in increasing order.
    #[inline]
    pub fn iter(&self) -> ScopeIter {
        ScopeIter {
            words: self.words,
            word: 0,
        }
    }

    #[inline]
    fn zip(&self, other: &Scope, f: impl Fn(u64, u64) -> u64) -> Scope {
        let mut words = [0; WORDS];
        for (i, w) in words.iter_mut().enumerate() {
            *w = f(self.words[i], other.words[i]);
        }
        Scope { words }
    }
}

/// Iterator over the DOF indices of a [`Scope`], in increasing order.
pub struct ScopeIter {
    words: [u64; WORDS],
    word: usize,
}

impl Iterator for ScopeIter {
    type Item = usize;
    #[inline]
    fn next(&mut self) -> Option<usize> {
        while self.word < WORDS {
            let w = self.words[self.word];
            if w != 0 {
                let bit = w.trailing_zeros() as usize;
                self.words[self.word] &= w - 1;
                return Some(self.word * 64 + bit);
            }
            self.word += 1;
        }
        None
    }
}

impl FromIterator<usize> for Scope {
    fn from_iter<I: IntoIterator<Item = usize>>(iter: I) -> Self {
        Scope::from_indices(iter)
    }
}

impl fmt::Debug for Scope {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_set().entries(self.iter()).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn set_operations() {
        let a = Scope::range(0..10);
        let b = Scope::range(5..70);
        assert_eq!(a.union(&b), Scope::range(0..70));
        assert_eq!(a.intersection(&b), Scope::range(5..10));
        assert_eq!(a.difference(&b), Scope::range(0..5));
        assert!(a.overlaps(&b));
        assert!(!Scope::range(0..5).overlaps(&Scope::range(5..9)));
        assert_eq!(b.len(), 65);
        assert!(Scope::range(0..70).contains_all(&a));
        assert_eq!(
            Scope::from_indices([3, 64, 200]).iter().collect::<Vec<_>>(),
            vec![3, 64, 200]
        );
    }

    proptest! {
        #[test]
        fn iteration_matches_membership(indices in proptest::collection::vec(0usize..MAX_DOFS, 0..40)) {
            let s = Scope::from_indices(indices.iter().copied());
            let mut sorted = indices.clone();
            sorted.sort_unstable();
            sorted.dedup();
            prop_assert_eq!(s.iter().collect::<Vec<_>>(), sorted.clone());
            prop_assert_eq!(s.len(), sorted.len());
            for i in 0..MAX_DOFS {
                prop_assert_eq!(s.contains(i), sorted.binary_search(&i).is_ok());
            }
        }

        #[test]
        fn overlap_is_nonempty_intersection(a in proptest::collection::vec(0usize..MAX_DOFS, 0..20),
                                            b in proptest::collection::vec(0usize..MAX_DOFS, 0..20)) {
            let (a, b) = (Scope::from_indices(a), Scope::from_indices(b));
            prop_assert_eq!(a.overlaps(&b), !a.intersection(&b).is_empty());
            prop_assert!(a.difference(&b).intersection(&b).is_empty());
        }
    }
}
