"""codegen.native: the C entry point called on buffers gives CasADi's own numbers, bit for bit."""
import casadi as ca
import numpy as np
import pytest

from swim_model import codegen


def functions():
    """An SX function with a matrix output and an MX function looping a step (as the simulator's period)."""
    x, u, h = ca.SX.sym("x", 3), ca.SX.sym("u", 2), ca.SX.sym("h")
    xdot = ca.vertcat(x[1], -ca.sin(x[0]) + u[0] * ca.cos(x[2]), u[1] - 0.1 * x[2] ** 3)
    step = ca.Function("codegen_test_step", [x, u, h], [x + h * xdot])
    outer = ca.Function("codegen_test_outer", [x, u], [x @ u.T, ca.sumsqr(x)])
    x0, u0, h0 = ca.MX.sym("x", 3), ca.MX.sym("u", 2), ca.MX.sym("h")
    states = step.mapaccum(5)(x0, ca.repmat(u0, 1, 5), ca.repmat(h0, 1, 5))
    period = ca.Function("codegen_test_period", [x0, u0, h0], [states[:, -1], ca.mmin(states[0, :])])
    return [step, outer, period]


@pytest.mark.parametrize("compiled", [True, False], ids=["C entry point", "no compiler: CasADi"])
def test_native_calls_match_casadi_bit_for_bit(compiled, tmp_path, monkeypatch):
    monkeypatch.setenv("SWIM_CACHE_DIR", str(tmp_path))
    reference = functions()
    if compiled:
        native = codegen.native(reference, tag="codegen_test")
        assert list(tmp_path.glob("codegen_test_*.so"))
    else:
        native = {f.name(): codegen.NativeFunction(f) for f in reference}
    rng = np.random.default_rng(5)
    for function in reference:
        fast = native[function.name()]
        for _ in range(20):
            arguments = [rng.normal(size=function.nnz_in(i)) for i in range(function.n_in())]
            for buffer, value in zip(fast.inputs, arguments):
                buffer[:] = value
            fast()
            expected = function.call([ca.DM(a) for a in arguments])
            for got, want in zip(fast.outputs, expected):
                np.testing.assert_array_equal(got, np.asarray(want).ravel(order="F"))


def test_sparse_arguments_are_refused():
    x = ca.SX.sym("x", ca.Sparsity.diag(3))
    with pytest.raises(ValueError, match="sparse"):
        codegen.NativeFunction(ca.Function("sparse_in", [x], [ca.sum1(x)]))
