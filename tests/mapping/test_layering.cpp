// The code's layering, read from the sources: mapping/'s folders include each other in one
// direction (docs/dev/architecture.md gives the order), and the libraries include nothing of the
// layers above them (mapping: no GL, GLFW, ImGui, render/ or app/; render: no GLFW, ImGui or app/).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using FolderGraph = std::map<std::string, std::set<std::string>>;

struct Include {
  fs::path file;
  std::string target;  ///< what is between the quotes or angle brackets
};

std::vector<Include> includesUnder(const fs::path& dir) {
  static const std::regex kInclude(R"(^\s*#\s*include\s*[<"]([^">]+)[">])");
  std::vector<Include> out;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".h" && ext != ".cpp" && ext != ".inc") continue;
    std::ifstream in(entry.path());
    std::smatch m;
    for (std::string line; std::getline(in, line);)
      if (std::regex_search(line, m, kInclude)) out.push_back({entry.path(), m[1]});
  }
  return out;
}

// Folder of mapping/ that `file` lives in, or of an include "mapping/FOLDER/...".
std::string folderOf(const fs::path& relative_to_mapping) { return relative_to_mapping.begin()->string(); }

FolderGraph mappingFolderGraph() {
  const fs::path mapping = fs::path(VDMAP_SOURCE_DIR) / "mapping";
  FolderGraph graph;
  for (const Include& inc : includesUnder(mapping)) {
    const std::string from = folderOf(fs::relative(inc.file, mapping));
    graph[from];
    if (inc.target.rfind("mapping/", 0) != 0) continue;
    const std::string to = folderOf(fs::path(inc.target.substr(8)));
    if (to != from) graph[from].insert(to);
  }
  return graph;
}

// A cycle of `graph` as "a -> b -> a", or "" when it has none (depth-first search).
std::string findCycle(const FolderGraph& graph) {
  std::map<std::string, int> state;  // 0 unseen, 1 on the path, 2 done
  std::vector<std::string> path;
  std::string cycle;
  auto visit = [&](auto&& self, const std::string& node) -> bool {
    state[node] = 1;
    path.push_back(node);
    const auto it = graph.find(node);
    if (it != graph.end())
      for (const std::string& next : it->second) {
        if (state[next] == 1) {
          auto start = std::find(path.begin(), path.end(), next);
          for (auto p = start; p != path.end(); ++p) cycle += *p + " -> ";
          cycle += next;
          return true;
        }
        if (state[next] == 0 && self(self, next)) return true;
      }
    path.pop_back();
    state[node] = 2;
    return false;
  };
  for (const auto& [node, edges] : graph)
    if (state[node] == 0 && visit(visit, node)) return cycle;
  return "";
}

TEST(Layering, TheCycleSearchFindsACycleAndPassesAnOrder) {
  EXPECT_EQ(findCycle({{"a", {"b"}}, {"b", {"c"}}, {"c", {}}}), "");
  EXPECT_EQ(findCycle({{"a", {"b"}}, {"b", {"c"}}, {"c", {"a"}}}), "a -> b -> c -> a");
  EXPECT_EQ(findCycle({{"a", {"b", "c"}}, {"b", {"c"}}, {"c", {"b"}}}), "b -> c -> b");
}

TEST(Layering, MappingFoldersIncludeEachOtherInOneDirection) {
  const FolderGraph graph = mappingFolderGraph();
  ASSERT_GE(graph.size(), 8u) << "mapping/ not found under " << VDMAP_SOURCE_DIR;
  EXPECT_EQ(findCycle(graph), "") << "mapping/'s folders include each other in a cycle";
}

// mapping/'s folders in the order docs/dev/architecture.md's table lists them (rows "| `NAME/` |"
// under "## `mapping/`").
std::vector<std::string> documentedMappingOrder() {
  std::ifstream in(fs::path(VDMAP_SOURCE_DIR) / "docs/dev/architecture.md");
  static const std::regex kRow(R"(^\| `([a-z_]+)/` \|)");
  std::vector<std::string> order;
  bool in_section = false;
  std::smatch m;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("## ", 0) == 0) in_section = line == "## `mapping/`";
    if (in_section && std::regex_search(line, m, kRow)) order.push_back(m[1]);
  }
  return order;
}

TEST(Layering, MappingFoldersIncludeOnlyTheFoldersTheArchitectureListsBeforeThem) {
  const FolderGraph graph = mappingFolderGraph();
  const std::vector<std::string> order = documentedMappingOrder();
  auto rank = [&](const std::string& folder) { return std::find(order.begin(), order.end(), folder) - order.begin(); };
  for (const auto& [folder, includes] : graph) {
    ASSERT_LT(rank(folder), static_cast<long>(order.size()))
        << "docs/dev/architecture.md does not list mapping/" << folder;
    for (const std::string& to : includes)
      EXPECT_LT(rank(to), rank(folder)) << "mapping/" << folder << " includes mapping/" << to
                                        << ", which docs/dev/architecture.md lists after it";
  }
}

// Files under `dir` that include a header whose path starts with one of `banned`.
std::vector<std::string> bannedIncludes(const std::string& dir, const std::vector<std::string>& banned) {
  std::vector<std::string> out;
  for (const Include& inc : includesUnder(fs::path(VDMAP_SOURCE_DIR) / dir))
    for (const std::string& prefix : banned)
      if (inc.target.rfind(prefix, 0) == 0) out.push_back(inc.file.string() + ": " + inc.target);
  return out;
}

TEST(Layering, TheMappingLibraryIncludesNoGlWindowOrLayerAbove) {
  EXPECT_EQ(bannedIncludes("mapping", {"GL/", "GLFW/", "glm/", "imgui", "render/", "app/"}),
            std::vector<std::string>{});
}

TEST(Layering, TheRendererIncludesNoWindowToolkitOrApp) {
  EXPECT_EQ(bannedIncludes("render", {"GLFW/", "imgui", "app/"}), std::vector<std::string>{});
}

// app/'s rooms, lowest first: cli/ and query_files/ include no other room; view/ (the headless
// view) only cli/; workbench/ (the window's model) and bench/ only cli/ and view/; window/ alone
// includes GLFW and ImGui. The benchmark programs include nothing of app/.
TEST(Layering, AppRoomsIncludeOnlyTheRoomsBelowThem) {
  const std::vector<std::string> toolkit = {"GLFW/", "imgui"};
  auto plus = [](std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  const std::vector<std::string> nothing;
  EXPECT_EQ(bannedIncludes("app/cli",
                           plus(toolkit, {"app/view", "app/query_files", "app/workbench", "app/window", "app/bench"})),
            nothing);
  EXPECT_EQ(bannedIncludes("app/query_files",
                           plus(toolkit, {"app/cli", "app/view", "app/workbench", "app/window", "app/bench"})),
            nothing);
  EXPECT_EQ(bannedIncludes("app/view", plus(toolkit, {"app/query_files", "app/workbench", "app/window", "app/bench"})),
            nothing);
  EXPECT_EQ(bannedIncludes("app/workbench", plus(toolkit, {"app/window", "app/bench"})), nothing);
  EXPECT_EQ(bannedIncludes("app/bench", plus(toolkit, {"app/window", "app/workbench"})), nothing);
  EXPECT_EQ(bannedIncludes("benchmarks", {"app/"}), nothing);
}

// A folder's detail/ headers are its own: other folders of the libraries do not include them
// (tests and benchmarks may, to check and time the parts).
TEST(Layering, DetailHeadersAreIncludedOnlyByTheirFolder) {
  const fs::path root(VDMAP_SOURCE_DIR);
  std::vector<std::string> outside;
  for (const char* dir : {"mapping", "render", "app"})
    for (const Include& inc : includesUnder(root / dir)) {
      const auto detail = inc.target.find("/detail/");
      if (detail == std::string::npos) continue;
      const std::string owner = inc.target.substr(0, detail);  // e.g. mapping/query
      const std::string from = fs::relative(inc.file, root).generic_string();
      if (from.rfind(owner + "/", 0) != 0) outside.push_back(from + ": " + inc.target);
    }
  EXPECT_EQ(outside, std::vector<std::string>{});
}

}  // namespace
