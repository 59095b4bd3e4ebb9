//! Relative paths of an experiment file resolved once, where the file is
//! read: every file an experiment names (logs, bags, residual tables, rover
//! descriptions, the reference table, replayed VO, plug-in programs and
//! scripts) is made absolute against the experiment file's folder, so that
//! nothing downstream needs to know where the file was.

use std::path::{Component, Path, PathBuf};

use gpodo_frontends::params::VoSpec;
use gpodo_regressors::RegressorSpec;

use super::{DatasetSpec, ExperimentConfig, MotionModelSpec};

/// `path` against `base` (itself made absolute against the working
/// folder), with `.` and `..` folded away lexically (no symbolic link is
/// followed, and the file need not exist). An absolute `path` is kept.
pub fn resolve(base: &Path, path: &Path) -> PathBuf {
    if path.is_absolute() {
        return path.to_path_buf();
    }
    let joined = std::path::absolute(base)
        .unwrap_or_else(|_| base.to_path_buf())
        .join(path);
    let mut out = PathBuf::new();
    for part in joined.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir => {
                if matches!(out.components().next_back(), Some(Component::Normal(_))) {
                    out.pop();
                } else {
                    out.push(part);
                }
            }
            other => out.push(other),
        }
    }
    out
}

fn resolve_all(base: &Path, paths: &mut [PathBuf]) {
    for p in paths {
        *p = resolve(base, p);
    }
}

fn resolve_regressor(base: &Path, spec: &mut RegressorSpec) {
    if let RegressorSpec::External(p) = spec {
        *p = p
            .clone()
            .resolved_against(&std::path::absolute(base).unwrap_or_else(|_| base.to_path_buf()));
    }
}

impl ExperimentConfig {
    /// This experiment with every relative path resolved against `base`,
    /// the folder of the file it was read from.
    #[must_use]
    pub fn with_paths_resolved(mut self, base: &Path) -> Self {
        let absolute = std::path::absolute(base).unwrap_or_else(|_| base.to_path_buf());
        let base = absolute.as_path();
        match &mut self.dataset {
            DatasetSpec::Simulated { .. } => {}
            DatasetSpec::Logs { train, test } | DatasetSpec::Bags { train, test, .. } => {
                resolve_all(base, train);
                resolve_all(base, test);
            }
            DatasetSpec::ResidualTable { path, .. } => *path = resolve(base, path),
        }
        match &mut self.motion_model {
            MotionModelSpec::WeightedJacobian { rover, .. }
            | MotionModelSpec::SkidSteer { rover, .. }
            | MotionModelSpec::ReportedOdometry { rover, .. } => {
                if let Some(p) = rover {
                    *p = resolve(base, p);
                }
            }
        }
        if let Some(reference) = &mut self.compare_with {
            reference.path = resolve(base, &reference.path);
        }
        for spec in self
            .regressors
            .iter_mut()
            .chain(self.absolute_regressors.iter_mut())
        {
            resolve_regressor(base, spec);
        }
        for scheme in &mut self.schemes {
            if let Some(online) = &mut scheme.online {
                resolve_regressor(base, &mut online.regressor);
            }
        }
        // An empty replay path means the VO recorded with each run.
        if let VoSpec::Replay(p) = &mut self.frontend.vo
            && !p.path.as_os_str().is_empty()
        {
            p.path = resolve(base, &p.path);
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_are_joined_and_folded_and_absolute_ones_kept() {
        let base = Path::new("/data/experiments");
        assert_eq!(
            resolve(base, Path::new("../../shared/t.csv")),
            PathBuf::from("/shared/t.csv")
        );
        assert_eq!(
            resolve(base, Path::new("./logs/a.csv")),
            PathBuf::from("/data/experiments/logs/a.csv")
        );
        assert_eq!(
            resolve(base, Path::new("/abs/b.mcap")),
            PathBuf::from("/abs/b.mcap")
        );
        assert!(resolve(Path::new("rel"), Path::new("x.csv")).is_absolute());
    }
}
