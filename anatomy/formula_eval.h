// Evaluates point formulas (anatomy/point_formula.h) against a resolved skeleton.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>

#include "anatomy/landmarks.h"
#include "anatomy/point_formula.h"

namespace rigbake {

struct FormulaContext {
  const Skeleton* skeleton = nullptr;
  const LandmarkSet* landmarks = nullptr;
  std::string side = "l";           // which side "clavicle" etc. mean
  double reference_height = 1.8;    // the height at which ref_m offsets are literal metres
  const std::map<std::string, Eigen::Vector3d>* locators = nullptr;  // for {"locator": ...}
  std::string file;                 // for messages
};

// Throws LANDMARK_UNRESOLVED (a formula needs a landmark the skeleton lacks) or PRESET_INVALID
// (a locator reference that was not placed before).
Eigen::Vector3d evaluateFormula(const PointFormula& formula, const FormulaContext& context);

// Whether every landmark the formula needs is resolved (derivations try alternatives with it).
bool formulaInputsResolved(const PointFormula& formula, const LandmarkSet& landmarks, const std::string& side);

}  // namespace rigbake
