// The generated tables of the manual: docs/models.md and docs/integrators.md each hold the
// output of `stiffbench list models|integrators --format markdown` (write_catalog_markdown)
// between the marker lines
//   <!-- BEGIN GENERATED: stiffbench list models --format markdown -->
//   <!-- END GENERATED -->
// This test regenerates each table and fails, naming the file and the command that refreshes
// it, when the checked-in copy differs (a model or integrator was added, renamed or
// re-described without updating the manual). With STIFFBENCH_REFRESH_DOCS=1 in the environment
// it rewrites the stale sections instead of failing.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "core/types.hpp"
#include "experiments/build_info.hpp"
#include "experiments/commands/catalog_markdown.hpp"

namespace {

namespace fs = std::filesystem;

const fs::path kSourceDir = STIFFBENCH_SOURCE_DIR;

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string begin_marker(const std::string& what) {
  return "<!-- BEGIN GENERATED: stiffbench list " + what + " --format markdown -->\n";
}
const std::string kEndMarker = "<!-- END GENERATED -->";

// Compares the section of docs/FILE between the markers with the regenerated table.
void check_generated_section(const std::string& what, const std::string& file) {
  const fs::path path = kSourceDir / "docs" / file;
  const std::string refresh = "`stiffbench list " + what +
                              " --format markdown` (or run this test with "
                              "STIFFBENCH_REFRESH_DOCS=1)";
  ASSERT_TRUE(fs::exists(path)) << path << " is missing";
  const std::string text = read_file(path);
  const std::string begin = begin_marker(what);
  const auto b = text.find(begin);
  ASSERT_NE(b, std::string::npos) << "docs/" << file << " has no line '"
                                  << begin.substr(0, begin.size() - 1) << "'";
  const auto start = b + begin.size();
  const auto e = text.find(kEndMarker, start);
  ASSERT_NE(e, std::string::npos) << "docs/" << file << " has no line '" << kEndMarker
                                  << "' after its BEGIN GENERATED marker";

  std::ostringstream generated;
  stiffbench::write_catalog_markdown(what, generated);
  const std::string checked_in = text.substr(start, e - start);
  if (checked_in == generated.str()) return;

  const char* refresh_env = std::getenv("STIFFBENCH_REFRESH_DOCS");
  if (refresh_env != nullptr && std::string(refresh_env) == "1") {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << text.substr(0, start) << generated.str() << text.substr(e);
    ASSERT_TRUE(out.good()) << "cannot rewrite " << path;
    return;
  }
  ADD_FAILURE() << "docs/" << file << " is stale: the table between its GENERATED markers "
                << "differs from the registries. Replace it with the output of " << refresh
                << ".\n--- generated ---\n"
                << generated.str();
}

TEST(GeneratedDocs, ModelsTableMatchesRegistry) { check_generated_section("models", "models.md"); }

TEST(GeneratedDocs, IntegratorsTableMatchesRegistry) {
  check_generated_section("integrators", "integrators.md");
}

TEST(GeneratedDocs, UnknownCatalogueIsBadInput) {
  std::ostringstream out;
  EXPECT_THROW(stiffbench::write_catalog_markdown("experiments", out), stiffbench::BadInput);
}

}  // namespace
