#include "anatomy/formula_eval.h"

#include <cassert>

#include "core/error.h"

namespace rigbake {

Eigen::Vector3d evaluateFormula(const PointFormula& formula, const FormulaContext& context) {
  const LandmarkSet& landmarks = *context.landmarks;
  const double scale = landmarks.body.height / context.reference_height;
  auto landmarkOf = [&](const std::string& name) -> const Landmark& {
    std::string full = sidedName(name, context.side);
    if (!landmarks.has(full))
      fail(errc::LANDMARK_UNRESOLVED, context.file + "#" + formula.pointer,
           "landmark '" + full + "' is not resolved on this skeleton");
    return landmarks.get(full);
  };
  switch (formula.kind) {
    case PointFormula::Kind::kAt: return landmarkOf(formula.name).position;
    case PointFormula::Kind::kMean: {
      Eigen::Vector3d total = Eigen::Vector3d::Zero();
      for (const PointFormula& arg : formula.args) total += evaluateFormula(arg, context);
      return total / static_cast<double>(formula.args.size());
    }
    case PointFormula::Kind::kLerp: {
      Eigen::Vector3d a = evaluateFormula(formula.args[0], context);
      Eigen::Vector3d b = evaluateFormula(formula.args[1], context);
      return a + (b - a) * formula.t;
    }
    case PointFormula::Kind::kSum: {
      Eigen::Vector3d total = Eigen::Vector3d::Zero();
      for (const PointFormula& arg : formula.args) total += evaluateFormula(arg, context);
      return total;
    }
    case PointFormula::Kind::kDir:
      return landmarks.body.direction(formula.name, context.side) * (formula.ref_m * scale);
    case PointFormula::Kind::kJointAxis: {
      const Landmark& landmark = landmarkOf(formula.name);
      int column = formula.axis == "x" ? 0 : formula.axis == "y" ? 1 : 2;
      Eigen::Vector3d axis = context.skeleton->bind_world[landmark.joint].linear().col(column);
      return axis.normalized() * (formula.ref_m * scale);
    }
    case PointFormula::Kind::kMix: {
      const BodyFrame& body = landmarks.body;
      return body.lateral * evaluateFormula(formula.args[0], context).dot(body.lateral) +
             body.up * evaluateFormula(formula.args[1], context).dot(body.up) +
             body.forward * evaluateFormula(formula.args[2], context).dot(body.forward);
    }
    case PointFormula::Kind::kLocator: {
      auto it = context.locators ? context.locators->find(formula.name) : decltype(context.locators->end()){};
      if (!context.locators || it == context.locators->end())
        fail(errc::PRESET_INVALID, context.file + "#" + formula.pointer,
             "locator '" + formula.name + "' is not placed before this formula (use Part.origin or Part.insertion of an earlier part)");
      return it->second;
    }
  }
  assert(false);
  return Eigen::Vector3d::Zero();
}

bool formulaInputsResolved(const PointFormula& formula, const LandmarkSet& landmarks, const std::string& side) {
  if (formula.kind == PointFormula::Kind::kAt || formula.kind == PointFormula::Kind::kJointAxis) {
    if (!landmarks.has(sidedName(formula.name, side))) return false;
  }
  for (const PointFormula& arg : formula.args) {
    if (!formulaInputsResolved(arg, landmarks, side)) return false;
  }
  return true;
}

}  // namespace rigbake
