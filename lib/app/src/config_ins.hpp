#pragma once
// Config sections of the odometry/INS/vision method (seeds/004): `fusion.filter.ins`,
// `fusion.landmarks` and the top-level `landmarks` (the simulator's `ins_sim`: lcmloc_simconfig).
// Internal to lib/app/src (called from config.cpp).
#include <map>
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/yaml_reader.hpp"
#include "lcmloc/core/filter.hpp"

namespace lcmloc::app::ins_config {

void parseInsFilter(KeyReader& filter, core::InsFilterConfig& c);
/// A landmark map under parent.key: a list of {id, x, y} (x east, y north [m]), ids unique
/// (absent: out unchanged; null: empty).
void parseLandmarkList(KeyReader& parent, const std::string& key, std::vector<MapLandmark>& out);
/// `fusion.landmarks` (the same list) as id -> (x, y).
void parseLandmarks(KeyReader& fusion, std::map<int, core::Vec2>& landmarks);

}  // namespace lcmloc::app::ins_config
