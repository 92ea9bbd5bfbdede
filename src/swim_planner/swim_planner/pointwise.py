"""IPOPT on an NLP whose only nonlinearity is one small function evaluated at many points.

A collocation NLP in z (the states and inputs at every knot and midpoint) has the form

    min f(z, Phi)   s.t.  lbg <= g(z, Phi) <= ubg,      Phi_p = phi(y_p, theta),  y_p = S_p z   (p = 1..P)

with g affine in (z, Phi), f linear in Phi plus quadratic in z, and phi the model's pointwise function (state
derivative, torques, ...). With the constant matrices A = dg/dz, B = dg/dPhi, b = df/dPhi, Q = d2f/dz2,
S = dy/dz and the per-point J_p = dphi/dy(y_p), H_p = d2(w_p . phi)/dy2(y_p):

    grad f  = df/dz + S' blockdiag(J_p)' b
    jac g   = A + B blockdiag(J_p) S
    hess L  = sigma Q + S' blockdiag(H_p) S,      w = sigma b + B' lambda_g   (w_p: its entries at point p)

CasADi's own AD of the same graph (MX calls of mapped functions) builds a generic Hessian graph: 69 ms a call on
the 80-interval cruise, 2.6 of its 3.4 s. Here phi, J_p and H_p are compiled to C once per model
(swim_model.codegen, cached on disk) and evaluated over all points in one mapped call, about 1 ms; the rest is
two sparse products with constant matrices.
"""
from __future__ import annotations

import dataclasses
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from swim_model import codegen

Array = npt.NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class PointwiseFunction:
    """phi(y, theta) with its Jacobian dphi/dy and the Hessian d2(w . phi)/dy2, as CasADi functions."""

    value: ca.Function      # (y, theta) -> phi, m x 1
    symbolic: ca.Function   # the same phi in CasADi's SX, which CasADi can differentiate to any order
    jacobian: ca.Function   # (y, theta) -> dphi/dy, m x ny
    hessian: ca.Function    # (y, theta, w) -> d2(w . phi)/dy2, ny x ny (symmetric, both triangles)

    @classmethod
    def compiled(cls, phi: ca.SX, y: ca.SX, theta: ca.SX, tag: str) -> "PointwiseFunction":
        """The three functions of the SX expression phi(y, theta), compiled to C where it can be.

        Compiled once per machine (the library is cached under the hash of its source) or, without a C compiler, run in
        CasADi's virtual machine.
        """
        weights = ca.SX.sym("w", phi.numel())
        functions = [ca.Function(f"{tag}_phi", [y, theta], [phi]),
                     ca.Function(f"{tag}_jac", [y, theta], [ca.jacobian(phi, y)]),
                     ca.Function(f"{tag}_hess", [y, theta, weights], [ca.hessian(ca.dot(weights, phi), y)[0]])]
        # phi's own Jacobian, named jac_<phi> so that CasADi finds it: nlpsol differentiates its f and g once,
        # for the multipliers it reports at the end
        loaded = codegen.compiled(functions + [functions[0].jacobian()], tag)
        value, jacobian, hessian = (loaded[f.name()] for f in functions)
        return cls(value=value, symbolic=functions[0], jacobian=jacobian, hessian=hessian)


@dataclasses.dataclass(frozen=True)
class PointwiseNlp:
    """The NLP above.

    ``phi_placeholder`` is the m x P symbol standing for Phi in f and g; ``points`` the ny x P expression of the y_p in
    z; ``theta`` the value of phi's parameters.
    """

    z: ca.MX
    f: ca.MX
    g: ca.MX
    points: ca.MX
    phi_placeholder: ca.MX
    pointwise: PointwiseFunction
    theta: Array

    def phi_of_z(self, symbolic: bool = False) -> ca.MX:
        """Phi as an expression of z: one mapped call of phi (compiled, or the SX one) over the points."""
        phi = self.pointwise.symbolic if symbolic else self.pointwise.value
        return phi.map(self.points.shape[1])(self.points, self.theta)

    def substitute(self, *expressions: ca.MX, symbolic: bool = False) -> list[ca.MX]:
        """Expressions of (z, Phi) as expressions of z alone, sharing one evaluation of Phi."""
        return ca.substitute(list(expressions), [self.phi_placeholder], [self.phi_of_z(symbolic)])


def _constant(expression: ca.MX, symbols: list[ca.MX], what: str) -> ca.DM:
    """The value of an expression that must not depend on the symbols (raises if it does)."""
    for symbol in symbols:
        if ca.depends_on(expression, symbol):
            raise ValueError(f"pointwise NLP: {what} is not constant: f must be linear in Phi and quadratic in z, "
                             f"g affine in (z, Phi), the points linear in z")
    return ca.evalf(expression)


def _block_diagonal(block: ca.Sparsity, count: int) -> ca.Sparsity:
    """The sparsity of blockdiag(block, ..., block).

    Its nonzeros are ordered as those of a horizontal concatenation of the blocks (column-major, blocks in turn), which
    is what a mapped function returns.
    """
    return ca.kron(ca.DM.eye(count), ca.DM(block, 1.0)).sparsity()


@dataclasses.dataclass(frozen=True)
class Structure:
    """The constant matrices of the module docstring, and g's value at z = 0, Phi = 0."""

    a: ca.DM     # dg/dz
    b_g: ca.DM   # dg/dPhi (columns in the order of vec(Phi))
    b_f: ca.DM   # df/dPhi, a column
    q: ca.DM     # d2f/dz2
    s: ca.DM     # dy/dz, rows in the order of vec(points)
    g0: Array

    @classmethod
    def of(cls, nlp: PointwiseNlp) -> "Structure":
        """Raises ValueError if the NLP is not of the module docstring's form."""
        z, phi = nlp.z, nlp.phi_placeholder
        symbols = [z, phi]
        if ca.depends_on(ca.gradient(nlp.f, z), phi):
            raise ValueError("pointwise NLP: f has a term in both z and Phi")
        g0 = ca.substitute([nlp.g], symbols, [ca.MX.zeros(v.sparsity()) for v in symbols])[0]
        return cls(a=_constant(ca.jacobian(nlp.g, z), symbols, "dg/dz"),
                   b_g=_constant(ca.jacobian(nlp.g, phi), symbols, "dg/dPhi"),
                   b_f=_constant(ca.jacobian(nlp.f, phi), symbols, "df/dPhi").T,
                   q=_constant(ca.hessian(nlp.f, z)[0], symbols, "d2f/dz2"),
                   s=_constant(ca.jacobian(ca.vec(nlp.points), z), symbols, "dy/dz"),
                   g0=np.asarray(ca.evalf(g0), dtype=float).ravel())

    def rows(self, keep: list[int]) -> "Structure":
        """The same structure with only the constraint rows keep."""
        return dataclasses.replace(self, a=self.a[keep, :], b_g=self.b_g[keep, :], g0=self.g0[keep])


def derivative_functions(nlp: PointwiseNlp, structure: Structure) -> dict[str, ca.Function]:
    """IPOPT's grad_f, jac_g and hess_lag (nlpsol's signatures) assembled as in the module docstring."""
    z, phi, st = nlp.z, nlp.phi_placeholder, structure
    count = nlp.points.shape[1]
    jac_map = nlp.pointwise.jacobian.map(count)(nlp.points, nlp.theta)
    jac_blocks = ca.sparsity_cast(jac_map, _block_diagonal(nlp.pointwise.jacobian.sparsity_out(0), count))
    f_z, g_z, grad_f_z = nlp.substitute(nlp.f, nlp.g, ca.gradient(nlp.f, z))
    grad_f = grad_f_z + ca.mtimes(st.s.T, ca.mtimes(jac_blocks.T, st.b_f))
    jac_g = st.a + ca.mtimes(st.b_g, ca.mtimes(jac_blocks, st.s))
    p = ca.MX.sym("p", 0)
    sigma, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", nlp.g.numel())
    weights = ca.reshape(sigma * st.b_f + ca.mtimes(st.b_g.T, lam_g), phi.shape)
    hess_map = nlp.pointwise.hessian.map(count)(nlp.points, nlp.theta, weights)
    hess_blocks = ca.sparsity_cast(hess_map, _block_diagonal(nlp.pointwise.hessian.sparsity_out(0), count))
    hessian = sigma * st.q + ca.mtimes(st.s.T, ca.mtimes(hess_blocks, st.s))
    return {
        "grad_f": ca.Function("nlp_grad_f", [z, p], [f_z, grad_f], ["x", "p"], ["f", "grad_f_x"]),
        "jac_g": ca.Function("nlp_jac_g", [z, p], [g_z, jac_g], ["x", "p"], ["g", "jac_g_x"]),
        "hess_lag": ca.Function("nlp_hess_l", [z, p, sigma, lam_g], [ca.triu(hessian)],
                                ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"]),
    }


def simple_bounds(structure: Structure, lbg: Array, ubg: Array) -> tuple[list[int], Array, Array]:
    """The rows of g that bound a single variable, g_i = a z_j + c, as bounds on z_j.

    Several rows that bound one variable are intersected. IPOPT keeps a bound in its barrier term, with no row in its
    linear system. Returns the rows to keep as constraints, lbx and ubx.
    """
    a = structure.a.sparse().tocsr()
    coupled = np.diff(structure.b_g.sparse().tocsr().indptr) > 0
    lbx, ubx = np.full(a.shape[1], -np.inf), np.full(a.shape[1], np.inf)
    keep = []
    for row in range(a.shape[0]):
        start, stop = a.indptr[row], a.indptr[row + 1]
        if stop - start != 1 or coupled[row]:
            keep.append(row)
            continue
        column, slope = a.indices[start], a.data[start]
        low, high = sorted(((lbg[row] - structure.g0[row]) / slope, (ubg[row] - structure.g0[row]) / slope))
        low, high = max(lbx[column], low), min(ubx[column], high)
        if low > high:
            # rows that contradict each other by a rounding error (a state joined to another primitive's, which
            # met its own bound to IPOPT's tolerance): nlpsol refuses crossed bounds, IPOPT takes such rows
            keep.append(row)
            continue
        lbx[column], ubx[column] = low, high
    return keep, lbx, ubx


@dataclasses.dataclass(frozen=True)
class PointwiseResult:
    """What a pointwise solve returns: the solution z, IPOPT's return status and its iteration count."""

    z: Array
    status: str          # IPOPT's return status
    iterations: int


def solve(nlp: PointwiseNlp, z0: Array, lbg: Array, ubg: Array, ipopt_options: dict,
          derivatives: str = "pointwise", expand: bool = False) -> PointwiseResult:
    """Solve lbg <= g <= ubg, min f by IPOPT from z0, single-variable rows of g moved to bounds on z.

    derivatives "pointwise": the assembled ones of ``derivative_functions``; "casadi": CasADi's AD of the NLP
    written with the SX phi (``expand`` turns it into one SX graph first).
    """
    structure = Structure.of(nlp)
    lbg, ubg = np.asarray(lbg, dtype=float).ravel(), np.asarray(ubg, dtype=float).ravel()
    keep, lbx, ubx = simple_bounds(structure, lbg, ubg)
    nlp = dataclasses.replace(nlp, g=nlp.g[keep])
    symbolic = derivatives == "casadi"
    f_z, g_z = nlp.substitute(nlp.f, nlp.g, symbolic=symbolic)
    problem = {"x": nlp.z, "f": f_z, "g": g_z}
    options: dict[str, Any] = {"print_time": False, "ipopt": ipopt_options}
    if derivatives == "pointwise":
        options.update(derivative_functions(nlp, structure.rows(keep)))
    elif derivatives == "casadi":
        options["expand"] = expand
    else:
        raise ValueError(f"derivatives must be 'pointwise' or 'casadi', got {derivatives!r}")
    solver = ca.nlpsol("pointwise", "ipopt", problem, options)
    result = solver(x0=z0, lbx=lbx, ubx=ubx, lbg=lbg[keep], ubg=ubg[keep])
    stats = solver.stats()
    return PointwiseResult(z=np.asarray(result["x"], dtype=float).ravel(), status=str(stats["return_status"]),
                           iterations=int(stats["iter_count"]))
