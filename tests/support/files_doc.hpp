#pragma once
// docs/columns.md as a test oracle: the columns of a table budjam writes against those it lists,
// so that the documentation stays true.
#include <filesystem>
#include <string>
#include <vector>

namespace budjam::testing {

// The names in the header line of a CSV file.
std::vector<std::string> csv_header(const std::filesystem::path& file);

// The first-column names (`name`) of the table under the "## " heading of docs/columns.md that
// contains `key` (e.g. "`RUN/steps.csv`"); empty if there is no such heading.
std::vector<std::string> documented_columns(const std::string& key);

}  // namespace budjam::testing
