// `palpable impact SPEC.json`: resolves one collision described in JSON and prints the result as
// JSON (tools/lib/impact_spec.hpp documents the format; `palpable impact --help` prints it).
#include "core/check.hpp"
#include "tools/commands.hpp"
#include "tools/lib/atomic_file.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/lib/impact_spec.hpp"

#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <sstream>
#include <vector>

namespace {

std::string read_all(const std::string& path) {
  if (path == "-") {
    return std::string(std::istreambuf_iterator<char>(std::cin), std::istreambuf_iterator<char>());
  }
  std::ifstream in(path);
  if (!in) throw palpable::InputError(path, "cannot open the spec file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

palpable::tools::CommandRegistration registration{
    "impact", [](CLI::App& app) {
      app.description(
          "Resolve one collision (integration over the normal impulse with Coulomb friction, "
          "README \"How it works\") and print the result as JSON");
      app.footer(palpable::tools::kImpactSpecHelp);
      auto path = std::make_shared<std::string>();
      auto trajectory = std::make_shared<std::string>();
      app.add_option("spec", *path, "JSON spec file, or - for standard input")->required();
      app.add_option("--trajectory", *trajectory,
                     "also write u(p_z) along the integration as CSV (p_z,p_x,p_y,u_x,u_y,u_z, "
                     "contact frame: the hodographs of Routh and Stronge); written only when the "
                     "status is ok, atomically like run's files");
      return std::function<int()>([path, trajectory] {
        if (palpable::tools::names_descriptor(*trajectory) == 1) {  // "-", /dev/stdout
          throw palpable::InputError("--trajectory",
                                     "standard output carries the result; name a file");
        }
        const palpable::tools::ImpactSpec spec = palpable::tools::parse_impact_spec_text(
            read_all(*path), *path == "-" ? "<stdin>" : *path);
        std::unique_ptr<palpable::tools::AtomicFile> file;
        if (!trajectory->empty()) file = std::make_unique<palpable::tools::AtomicFile>(*trajectory);
        std::vector<palpable::ImpulsePathPoint> points;
        const nlohmann::json result =
            palpable::tools::resolve_impact(spec, file ? &points : nullptr);
        const bool ok = result["status"] == "ok";
        if (file && ok) {
          palpable::tools::write_impulse_path_csv(file->stream(), points);
          file->commit();
        }
        std::cout << result.dump() << "\n";
        return ok ? palpable::tools::kExitOk : palpable::tools::kExitFailure;
      });
    }};

}  // namespace
