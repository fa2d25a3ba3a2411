#pragma once
// Plain-text CSV reading shared by the importers (lcmloc-import, lcmloc-import-vp) and the
// fusion daemon's map file: one header row, comma-separated fields, refusals with line numbers.
#include <fstream>
#include <string>
#include <vector>

#include "lcmloc/core/types.hpp"

namespace lcmloc::app::csv {

/// Fields of one line split at commas; a trailing '\r' is dropped, spaces and tabs around each
/// field are trimmed. An empty line gives no fields.
std::vector<std::string> split(const std::string& line);

/// A finite number, or false with why ("column c: not a number: '...'" / "not finite").
bool parseNumber(const std::string& field, std::size_t column, double& out, std::string& why);

/// One data row of exactly n numbers, or false with why (wrong column count, not a number,
/// not finite, empty field).
bool parseRow(const std::string& line, std::size_t n, std::vector<double>& out, std::string& why);

/// Opens path and checks that its first line is exactly header. Throws std::runtime_error.
std::ifstream openWithHeader(const std::string& path, const std::string& header);

/// Opens a CSV file and reads its first line into header, without a leading UTF-8 byte-order
/// mark (EF BB BF, as spreadsheet programs write) and a trailing '\r'; the stream is left at the
/// second line (failed when the file is empty). Throws std::runtime_error "'path': reason" when
/// path is missing, a directory or not a regular file, or cannot be opened.
std::ifstream openCsv(const std::string& path, std::string& header);

/// A map file: header "id,x,y", one marker / landmark / beacon per row, id an integer >= 0,
/// x and y in metres in the local frame. Throws std::runtime_error naming file, line and reason
/// for any bad row (not a number, not finite), a duplicate id, or a marker far outside the rest
/// (farMarker): a map is configuration, nothing is skipped. Time O(n log n) in the rows.
core::MarkerMap loadMap(const std::string& path);

/// Where a map's markers are: the median point (median x, median y) and the spread, the median
/// distance of the markers from it. Both hold whatever a few wrong rows say. All 0 with fewer
/// than three markers.
struct MapSpread {
  double cx = 0.0, cy = 0.0, spread = 0.0;
};
MapSpread mapSpread(const core::MarkerMap& map);

/// A marker is far outside the rest when no other marker lies within kFarSpreads times the map's
/// spread of it (a road's spread is a quarter of its length; a cloud's, about its radius).
inline constexpr double kFarSpreads = 8.0;
/// The first marker (in map order) far outside the rest, -1: none (nor with fewer than three
/// markers or a spread of 0, more than half of them at one point). O(n log n).
long farMarker(const core::MarkerMap& map, const MapSpread& spread);

/// Writes a map file (header "id,x,y"; each coordinate the shortest text that reads back to the
/// same double, so loadMap gives map again exactly). Throws std::runtime_error.
void writeMap(const std::string& path, const core::MarkerMap& map);

}  // namespace lcmloc::app::csv
