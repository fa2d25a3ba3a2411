#pragma once
// Plain-text CSV reading shared by the importers (lcmloc-import, lcmloc-import-vp) and the
// fusion daemon's map file: one header row, comma-separated fields, refusals with line numbers.
#include <fstream>
#include <string>
#include <vector>

#include "lcmloc/core/types.hpp"

namespace lcmloc::common::csv {

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
/// for any bad row or a duplicate id (a map is configuration: nothing is skipped).
core::MarkerMap loadMap(const std::string& path);

/// Writes a map file (header "id,x,y"; each coordinate the shortest text that reads back to the
/// same double, so loadMap gives map again exactly). Throws std::runtime_error.
void writeMap(const std::string& path, const core::MarkerMap& map);

}  // namespace lcmloc::common::csv
