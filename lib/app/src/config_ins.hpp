#pragma once
// Config sections of the odometry/INS/vision method (seeds/004): `ins_sim`, `fusion.filter.ins`
// and `fusion.landmarks`. Internal to lib/app/src (called from config.cpp).
#include <map>

#include "lcmloc/app/yaml_reader.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/sim/ins_sim.hpp"
#include "lcmloc/sim/vision_sensor.hpp"

namespace lcmloc::common::ins_config {

void parseInsSim(KeyReader& root, models::InsSimConfig& c);
void parseInsFilter(KeyReader& filter, core::InsFilterConfig& c);
/// A landmark map under parent.key: a list of {id, x, y} (x east, y north [m]), ids unique
/// (absent: out unchanged; null: empty).
void parseLandmarkList(KeyReader& parent, const std::string& key, std::vector<models::Landmark>& out);
/// `fusion.landmarks` (the same list) as id -> (x, y).
void parseLandmarks(KeyReader& fusion, std::map<int, core::Vec2>& landmarks);

}  // namespace lcmloc::common::ins_config
