//! What corresponds between the reference and the candidate, by name: joints (the same
//! name, else the same under the retarget naming rule: without case and namespace,
//! `rigport_ik::naming::same_joint_name`), meshes, clips and morph targets (the same
//! name, then the rest in order), and what is on one side only.

use rigport_compare::deviation::JointPair;
use rigport_model::Skeleton;

/// Items paired by name, then the unpaired ones in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Paired {
    /// `(reference, candidate, by name)`, in reference order.
    pub pairs: Vec<(usize, usize, bool)>,
    /// Reference items left over.
    pub only_reference: Vec<usize>,
    /// Candidate items left over.
    pub only_candidate: Vec<usize>,
}

/// Pairs `reference` with `candidate` names: equal names first, then the rest in order
/// when `by_order` (meshes, clips), else left unpaired.
pub(crate) fn pair_names(reference: &[&str], candidate: &[&str], by_order: bool) -> Paired {
    let mut taken = vec![false; candidate.len()];
    let mut of_ref: Vec<Option<(usize, bool)>> = vec![None; reference.len()];
    for (r, name) in reference.iter().enumerate() {
        if let Some(c) = (0..candidate.len()).find(|&c| !taken[c] && candidate[c] == *name) {
            taken[c] = true;
            of_ref[r] = Some((c, true));
        }
    }
    if by_order {
        let mut free = (0..candidate.len())
            .filter(|&c| !taken[c])
            .collect::<Vec<_>>()
            .into_iter();
        for slot in of_ref.iter_mut().filter(|s| s.is_none()) {
            match free.next() {
                Some(c) => {
                    taken[c] = true;
                    *slot = Some((c, false));
                }
                None => break,
            }
        }
    }
    collect(of_ref, &taken)
}

/// Pairs joints: the same name, then the same bare name without case (each candidate
/// joint once), and for each pair its parents' pair.
pub(crate) fn pair_joints(reference: &Skeleton, candidate: &Skeleton) -> (Paired, Vec<JointPair>) {
    let rn: Vec<&str> = reference.joints().iter().map(|j| j.name.as_str()).collect();
    let cn: Vec<&str> = candidate.joints().iter().map(|j| j.name.as_str()).collect();
    let mut paired = pair_names(&rn, &cn, false);
    let mut taken = vec![false; cn.len()];
    for &(_, c, _) in &paired.pairs {
        taken[c] = true;
    }
    let mut rest = Vec::new();
    for &r in &paired.only_reference {
        match (0..cn.len())
            .find(|&c| !taken[c] && rigport_ik::naming::same_joint_name(rn[r], cn[c]))
        {
            Some(c) => {
                taken[c] = true;
                paired.pairs.push((r, c, false));
            }
            None => rest.push(r),
        }
    }
    paired.pairs.sort_unstable();
    paired.only_reference = rest;
    paired.only_candidate = (0..cn.len()).filter(|&c| !taken[c]).collect();
    let candidate_of: std::collections::HashMap<usize, usize> =
        paired.pairs.iter().map(|&(r, c, _)| (r, c)).collect();
    let parents: Vec<Option<usize>> = reference.parents().map(|p| p.map(|p| p.get())).collect();
    let joints = paired
        .pairs
        .iter()
        .map(|&(r, c, _)| JointPair {
            reference: r,
            candidate: c,
            parent: parents
                .get(r)
                .copied()
                .flatten()
                .and_then(|p| candidate_of.get(&p).map(|&pc| (p, pc))),
        })
        .collect();
    (paired, joints)
}

/// The pairs and the leftovers.
fn collect(of_ref: Vec<Option<(usize, bool)>>, taken: &[bool]) -> Paired {
    let mut paired = Paired::default();
    for (r, slot) in of_ref.into_iter().enumerate() {
        match slot {
            Some((c, by_name)) => paired.pairs.push((r, c, by_name)),
            None => paired.only_reference.push(r),
        }
    }
    paired.only_candidate = (0..taken.len()).filter(|&c| !taken[c]).collect();
    paired
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_first_then_order() {
        let p = pair_names(&["walk", "run"], &["run", "jump", "idle"], true);
        assert_eq!(p.pairs, [(0, 1, false), (1, 0, true)]);
        assert_eq!(p.only_candidate, [2]);
        let p = pair_names(&["a", "b"], &["b"], false);
        assert_eq!((p.pairs, p.only_reference), (vec![(1, 0, true)], vec![0]));
    }
}
