// The walls' and obstacles' contact as a linear complementarity problem on the pressure
// system's rows (issue 39; docs/method.md, "Energy"): a wall pushes and never pulls. At the
// unknowns of the nodes in contact (walls.hpp, contact_rows) the pressure is p >= 0, and
// where a row is held at p = 0 the water may leave its wall, which it does when the
// system's residual there, w = A p - b, is >= 0; p w = 0 at every such row. With A the
// symmetric positive definite pressure matrix and the corrector the adjoint of the
// right-hand side, the corrected velocity is then a projection onto a convex set in the
// mass norm, which gains no energy where the rest of the step gains none (the node
// surface: none at any step; the sub-cell surface's ghost values still gain at small
// steps, docs/method.md). The release it replaces (a second solve with the released rows'
// wall flux dropped) broke that adjoint and gained energy at every wall impact (x15 at dt =
// 0.1 ms on the paper's 0.008 m mesh).
//
// The problem is solved by the primal-dual active set method (Hintermueller, Ito and
// Kunisch 2002, SIAM J. Optim. 13(3) 865-888; a semismooth Newton method): solve with the
// held rows at 0, hold the rows whose pressure came out negative, let go of the held rows
// whose w came out negative, and solve again until nothing changes. Away from obstacles the
// matrix is an M-matrix (the bilinear element's Laplacian: non-positive couplings; the ghost
// surface adds to the diagonal only), for which the method ends in finitely many rounds; a
// cut cell's sliver couples some nodes positively (pressure_system.hpp), and the rounds are
// capped (MAX_CONTACT_ROUNDS) and reported there.
#pragma once

#include "view.hpp"

namespace mpmflow {

// The rounds after which a step stops the active set and reports it (Report::unsettled):
// the contacts of a step settle in a few (docs/method.md, "Energy").
constexpr int MAX_CONTACT_ROUNDS = 50;

// The system with the rows zero(r) held at p = 0 (ELL form, cols n x ns, -1 = no column,
// centre slot the diagonal): vals0's values with every coupling of such a row (its row's
// off-diagonal entries and its column's entries in the other rows) removed, into vals. The
// matrix stays symmetric positive definite, and with b(r) = 0 at those rows its solution is
// 0 there and the other rows' solution with p = 0 at them.
void hold_at_zero(View<const index_t, 2> cols, View<const double, 2> vals0, View<const bool> zero,
                  View<double, 2> vals);

// One round of the active set, from the held rows zero of the solve just made into next:
// at the rows the contact constrains (candidate(r)) and this process decides (the row's
// node rows(r) flagged in owned; owned empty: every row), a free row whose x(r) is below
// -x_tolerance is held and a held row whose residual w = A x - b of the unmodified matrix
// (cols, vals0) is below -w_tolerance is let go; every other row keeps its state. The
// tolerances are the solve's own error in x and in w: without them a row within it could
// be let go and taken back for ever. Returns how many rows changed.
index_t update_active_set(View<const index_t, 2> cols, View<const double, 2> vals0,
                          View<const double> x, View<const double> b, View<const bool> candidate,
                          View<const index_t> rows, View<const bool> owned, double x_tolerance,
                          double w_tolerance, View<const bool> zero, View<bool> next);

}  // namespace mpmflow
