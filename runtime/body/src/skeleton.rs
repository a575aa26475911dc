//! The immutable skeleton: joints in topological order, 1-DOF axes with limits, segment
//! solids and named scopes. One `Arc<Skeleton>` is shared by every actor of a template
//! instance; per-actor state lives elsewhere (see [`crate::state`]).

use crate::error::{did_you_mean, Error, Result};
use crate::scope::{Scope, MAX_DOFS};
use crate::solid::Solid;
use glam::DVec3;
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;

/// What a DOF moves: a rotation about its axis or a translation along it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DofKind {
    /// Rotation in radians about the axis (right-hand rule).
    Rotation,
    /// Translation in metres along the axis.
    Translation,
}

/// One degree of freedom: a JOINT node of Scenelib (Appendix C).
#[derive(Clone, Debug, PartialEq)]
pub struct Dof {
    /// Stable, readable name, e.g. `r_elbow_flexion`.
    pub name: String,
    /// Index of the joint that carries it.
    pub joint: usize,
    /// Rotation or translation.
    pub kind: DofKind,
    /// Unit axis in the joint's frame.
    pub axis: DVec3,
    /// Lower limit (radians or metres; `-inf` when unlimited).
    pub min: f64,
    /// Upper limit (radians or metres; `+inf` when unlimited).
    pub max: f64,
}

impl Dof {
    /// Clamps `value` into the DOF's limits.
    #[inline]
    pub fn clamp(&self, value: f64) -> f64 {
        value.clamp(self.min, self.max)
    }
}

/// A joint: a frame placed at a fixed offset in its parent, moved by its DOFs in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// H-Anim name, e.g. `r_elbow`.
    pub name: String,
    /// Parent joint index (always smaller than this joint's index), `None` for the root.
    pub parent: Option<usize>,
    /// Position of the joint in its parent's frame when every DOF is zero.
    pub offset: DVec3,
    /// The joint's DOFs, applied in index order (the first one outermost).
    pub dofs: Range<usize>,
}

/// An immutable articulated body: the shared "Model" of the Model/Data split.
#[derive(Clone, Debug)]
pub struct Skeleton {
    name: String,
    joints: Vec<Joint>,
    dofs: Vec<Dof>,
    limits: Vec<(f64, f64)>,
    solids: Vec<(usize, Solid)>,
    scopes: BTreeMap<String, Scope>,
    joint_index: HashMap<String, usize>,
    dof_index: HashMap<String, usize>,
    end_sites: Vec<(usize, DVec3)>,
}

impl Skeleton {
    /// The template instance's name (e.g. `adult`).
    #[inline]
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Joints in topological order (parents first).
    #[inline]
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }
    /// All DOFs, grouped by joint in joint order.
    #[inline]
    pub fn dofs(&self) -> &[Dof] {
        &self.dofs
    }
    /// The (min, max) limits of every DOF, packed for the blend loop.
    #[inline]
    pub fn limits(&self) -> &[(f64, f64)] {
        &self.limits
    }
    /// Number of DOFs.
    #[inline]
    pub fn dof_count(&self) -> usize {
        self.dofs.len()
    }
    /// Segment solids with the index of the joint each is attached to.
    #[inline]
    pub fn solids(&self) -> &[(usize, Solid)] {
        &self.solids
    }
    /// End sites (finger tips, toe tips, head top) as (joint, offset in the joint frame).
    #[inline]
    pub fn end_sites(&self) -> &[(usize, DVec3)] {
        &self.end_sites
    }
    /// Named scopes, sorted by name.
    #[inline]
    pub fn scopes(&self) -> &BTreeMap<String, Scope> {
        &self.scopes
    }
    /// Total mass of the solids in kilograms.
    #[inline]
    pub fn total_mass(&self) -> f64 {
        self.solids.iter().map(|(_, s)| s.mass).sum()
    }
    /// The scope holding every DOF.
    #[inline]
    pub fn all(&self) -> Scope {
        Scope::range(0..self.dofs.len())
    }

    /// Index of the joint called `name`.
    pub fn joint(&self, name: &str) -> Result<usize> {
        self.joint_index
            .get(name)
            .copied()
            .ok_or_else(|| Error::UnknownJoint {
                name: name.to_string(),
                skeleton: self.name.clone(),
                hint: did_you_mean(name, self.joints.iter().map(|j| j.name.as_str())),
            })
    }

    /// Index of the DOF called `name`.
    pub fn dof(&self, name: &str) -> Result<usize> {
        self.dof_index
            .get(name)
            .copied()
            .ok_or_else(|| Error::UnknownDof {
                name: name.to_string(),
                skeleton: self.name.clone(),
                hint: did_you_mean(name, self.dofs.iter().map(|d| d.name.as_str())),
            })
    }

    /// Resolves a scope expression: terms joined by `+` (union), `-` (difference) and `&`
    /// (intersection), read left to right. A term is a named scope (`right_arm`), a joint
    /// name (its DOFs: `r_elbow`) or a DOF name (`r_elbow_flexion`).
    pub fn scope(&self, expr: &str) -> Result<Scope> {
        let mut result = Scope::EMPTY;
        let mut op = '+';
        let mut term = String::new();
        let apply = |op: char, term: &str, result: &mut Scope| -> Result<()> {
            let s = self.scope_term(term.trim(), expr)?;
            *result = match op {
                '+' => result.union(&s),
                '-' => result.difference(&s),
                _ => result.intersection(&s),
            };
            Ok(())
        };
        for c in expr.chars() {
            if matches!(c, '+' | '-' | '&') {
                apply(op, &term, &mut result)?;
                term.clear();
                op = c;
            } else {
                term.push(c);
            }
        }
        apply(op, &term, &mut result)?;
        Ok(result)
    }

    fn scope_term(&self, term: &str, expr: &str) -> Result<Scope> {
        if let Some(s) = self.scopes.get(term) {
            return Ok(*s);
        }
        if let Some(&j) = self.joint_index.get(term) {
            return Ok(Scope::range(self.joints[j].dofs.clone()));
        }
        if let Some(&d) = self.dof_index.get(term) {
            return Ok(Scope::from_indices([d]));
        }
        let name = if term.is_empty() {
            format!("{expr} (empty term)")
        } else {
            term.to_string()
        };
        Err(Error::UnknownScope {
            name,
            skeleton: self.name.clone(),
            known: self.scopes.keys().cloned().collect::<Vec<_>>().join(", "),
        })
    }

    /// The names of the DOFs of `scope`, in index order.
    pub fn dof_names(&self, scope: &Scope) -> Vec<&str> {
        scope
            .iter()
            .filter_map(|i| self.dofs.get(i).map(|d| d.name.as_str()))
            .collect()
    }

    /// The joints of the subtree rooted at `joint` (the joint included), in index order.
    pub fn subtree(&self, joint: usize) -> Vec<usize> {
        // Parents come before their children: one pass marks the subtree.
        let mut inside = vec![false; self.joints.len()];
        let mut joints = Vec::new();
        for (j, jt) in self.joints.iter().enumerate() {
            inside[j] = j == joint || jt.parent.is_some_and(|p| inside[p]);
            if inside[j] {
                joints.push(j);
            }
        }
        joints
    }

    /// The scope of the joints in the subtree rooted at `joint` (the joint included).
    pub fn subtree_scope(&self, joint: usize) -> Scope {
        let mut scope = Scope::EMPTY;
        for j in self.subtree(joint) {
            for d in self.joints[j].dofs.clone() {
                scope.insert(d);
            }
        }
        scope
    }
}

/// Builds a [`Skeleton`] joint by joint; validates names, order and sizes.
#[derive(Debug)]
pub struct SkeletonBuilder {
    skeleton: Skeleton,
}

impl SkeletonBuilder {
    /// Starts an empty skeleton called `name`.
    pub fn new(name: impl Into<String>) -> Self {
        SkeletonBuilder {
            skeleton: Skeleton {
                name: name.into(),
                joints: Vec::new(),
                dofs: Vec::new(),
                limits: Vec::new(),
                solids: Vec::new(),
                scopes: BTreeMap::new(),
                joint_index: HashMap::new(),
                dof_index: HashMap::new(),
                end_sites: Vec::new(),
            },
        }
    }

    /// Adds a joint under `parent` (by name; `None` for the root) and returns its index.
    pub fn joint(&mut self, name: &str, parent: Option<&str>, offset: DVec3) -> Result<usize> {
        let s = &mut self.skeleton;
        if s.joint_index.contains_key(name) {
            return Err(Error::Duplicate {
                what: "joint",
                name: name.into(),
            });
        }
        let parent = match parent {
            Some(p) => Some(
                s.joint_index
                    .get(p)
                    .copied()
                    .ok_or_else(|| Error::UnknownJoint {
                        name: p.to_string(),
                        skeleton: s.name.clone(),
                        hint: did_you_mean(p, s.joints.iter().map(|j| j.name.as_str())),
                    })?,
            ),
            None if s.joints.is_empty() => None,
            None => return Err(Error::Invalid("a skeleton has exactly one root".into())),
        };
        let index = s.joints.len();
        s.joints.push(Joint {
            name: name.to_string(),
            parent,
            offset,
            dofs: s.dofs.len()..s.dofs.len(),
        });
        s.joint_index.insert(name.to_string(), index);
        Ok(index)
    }

    /// Adds a DOF to the most recently added joint.
    pub fn dof(
        &mut self,
        name: &str,
        kind: DofKind,
        axis: DVec3,
        min: f64,
        max: f64,
    ) -> Result<usize> {
        let s = &mut self.skeleton;
        let joint = s
            .joints
            .len()
            .checked_sub(1)
            .ok_or_else(|| Error::Invalid(format!("DOF `{name}` added before any joint")))?;
        if s.dof_index.contains_key(name) {
            return Err(Error::Duplicate {
                what: "DOF",
                name: name.into(),
            });
        }
        if s.dofs.len() >= MAX_DOFS {
            return Err(Error::Invalid(format!(
                "skeleton `{}` exceeds {MAX_DOFS} DOFs",
                s.name
            )));
        }
        if min.partial_cmp(&max).is_none_or(|o| o.is_gt())
            || axis.length_squared() < 1e-12
            || !axis.is_finite()
        {
            return Err(Error::Invalid(format!(
                "DOF `{name}`: needs a non-zero axis and min ≤ max"
            )));
        }
        let index = s.dofs.len();
        s.dofs.push(Dof {
            name: name.to_string(),
            joint,
            kind,
            axis: axis.normalize(),
            min,
            max,
        });
        s.limits.push((min, max));
        s.joints[joint].dofs.end = index + 1;
        s.dof_index.insert(name.to_string(), index);
        Ok(index)
    }

    /// Attaches a solid to the joint called `joint`.
    pub fn solid(&mut self, joint: &str, solid: Solid) -> Result<()> {
        let j = self.skeleton.joint(joint)?;
        solid.shape.validate()?;
        self.skeleton.solids.push((j, solid));
        Ok(())
    }

    /// Adds an end site (a tip with no DOF) to the joint called `joint`.
    pub fn end_site(&mut self, joint: &str, offset: DVec3) -> Result<()> {
        let j = self.skeleton.joint(joint)?;
        self.skeleton.end_sites.push((j, offset));
        Ok(())
    }

    /// Names a scope from a scope expression over what has been built so far.
    pub fn scope(&mut self, name: &str, expr: &str) -> Result<Scope> {
        let scope = self.skeleton.scope(expr)?;
        self.skeleton.scopes.insert(name.to_string(), scope);
        Ok(scope)
    }

    /// Names a scope from an explicit DOF set.
    pub fn scope_from(&mut self, name: &str, scope: Scope) {
        self.skeleton.scopes.insert(name.to_string(), scope);
    }

    /// Read access to the skeleton under construction.
    pub fn current(&self) -> &Skeleton {
        &self.skeleton
    }

    /// Finishes the skeleton.
    pub fn build(self) -> Result<Skeleton> {
        if self.skeleton.joints.is_empty() {
            return Err(Error::Invalid(
                "a skeleton needs at least a root joint".into(),
            ));
        }
        Ok(self.skeleton)
    }
}
