// Levenberg-Marquardt for the QE fit's least-squares problems (qe_regularised.cpp), with
// parameters bounded below by zero.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <vector>

namespace pyrocam::qe_detail {

// Minimises |r(th)|^2 from th. Model: size(), fixed(k) (held where it is), bounded(k) (at least
// 0), evaluate(th, residual, jacobian or nullptr). Bounds below by zero (the leak bumps). A bounded
// parameter at zero whose gradient points outwards is held there, and one that a step would take
// below zero is held at zero and the step solved again for the rest (a Gauss-Newton step on the
// bounds' face). Clipping the step instead bent it off its descent direction: the set of held
// parameters changed from one iteration to the next and the fit crawled, stopping at max_iterations
// wherever it then was, so that a change of the data by a hundredth of a degree moved the
// readings above the furnace by tens of degrees. Returns the iterations taken.
template <class Model>
inline int levenberg_marquardt(const Model& model, Eigen::VectorXd& th, int max_iterations) {
  const Eigen::Index n = model.size();
  Eigen::VectorXd res, res_new;
  Eigen::MatrixXd jac;
  model.evaluate(th, res, &jac);
  double cost = res.squaredNorm(), mu = 1e-3;
  int it = 0;
  bool converged = false;
  for (; it < max_iterations && !converged; ++it) {
    const Eigen::VectorXd grad = jac.transpose() * res;
    // Most of the Jacobian is zero (a band's rows see its own parameters and shape changes).
    const Eigen::SparseMatrix<double> js = jac.sparseView();
    const Eigen::MatrixXd h = Eigen::MatrixXd(js.transpose() * js);
    std::vector<Eigen::Index> free;
    for (Eigen::Index k = 0; k < n; ++k)
      if (!model.fixed(k) && (!model.bounded(k) || th[k] > 0 || grad[k] < 0)) free.push_back(k);
    bool improved = false;
    for (int tries = 0; tries < 12 && !improved; ++tries) {
      std::vector<Eigen::Index> moving = free;
      Eigen::VectorXd held = Eigen::VectorXd::Zero(n);  // the change of those taken to zero
      Eigen::VectorXd trial;
      for (;;) {
        const auto nf = static_cast<Eigen::Index>(moving.size());
        Eigen::MatrixXd a = h(moving, moving);
        a.diagonal() += mu * (a.diagonal().array() + 1e-12).matrix();
        // The gradient of the linearised cost with the held ones at zero.
        const Eigen::VectorXd g = grad(moving) + (h * held)(moving);
        // Positive definite (mu > 0): Cholesky, blocked, rather than LDLT.
        const Eigen::LLT<Eigen::MatrixXd> llt(a);
        const Eigen::VectorXd step =
            llt.info() == Eigen::Success ? Eigen::VectorXd(llt.solve(-g)) : a.ldlt().solve(-g);
        std::vector<Eigen::Index> rest;
        for (Eigen::Index c = 0; c < nf; ++c) {
          const Eigen::Index k = moving[c];
          if (model.bounded(k) && th[k] + step[c] < 0)
            held[k] = -th[k];
          else
            rest.push_back(k);
        }
        if (rest.size() == moving.size() || rest.empty()) {
          trial = th + held;
          for (Eigen::Index c = 0; c < nf; ++c) trial[moving[c]] += step[c];
          for (Eigen::Index k = 0; k < n; ++k)
            if (model.bounded(k)) trial[k] = std::max(trial[k], 0.0);
          break;
        }
        moving = std::move(rest);
      }
      model.evaluate(trial, res_new, nullptr);
      const double c_new = res_new.squaredNorm();
      if (c_new < cost) {
        const double gain = cost - c_new;
        th = trial, mu = std::max(mu / 3, 1e-9);
        improved = true;
        converged = gain < 1e-10 * cost + 1e-14;
        cost = c_new;
        model.evaluate(th, res, &jac);
      } else {
        mu *= 4;
      }
    }
    if (!improved) break;
  }
  return it;
}

}  // namespace pyrocam::qe_detail
