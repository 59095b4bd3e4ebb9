"""scikit-learn's own estimator checks, on every gpodo estimator. The
checks that are expected to fail are listed with the reason."""

from sklearn.utils.estimator_checks import parametrize_with_checks

from gpodo import ILGR, ExactGP, SparseGP, StreamingSparseGP

# Small optimiser budgets keep the ~50 checks per estimator fast; the
# checks test conventions, not accuracy.
ESTIMATORS = [
    ExactGP(hyperopt={"max_iters": 20}),
    SparseGP(n_inducing=10, hyperopt={"max_iters": 20}),
    ILGR(),
    StreamingSparseGP(n_inducing=10, batch_iters=5, hyperopt={"max_iters": 20}),
]

# Every check passes: no estimator has an expected failure to list (the
# three that scikit-learn itself skips need SCIPY_ARRAY_API).
EXPECTED_FAILURES = {}


def expected_failed_checks(estimator):
    return EXPECTED_FAILURES.get(type(estimator).__name__, {})


@parametrize_with_checks(ESTIMATORS, expected_failed_checks=expected_failed_checks)
def test_sklearn_compatible_estimator(estimator, check):
    check(estimator)
