// uvpress: makes textured 3-D assets cheaper without making them look worse.
// Exit codes: 0 ok, 1 runtime or input error (one stderr line: file and reason), 2 usage.
#include "cli.h"

#include "core/error.h"
#include "core/report_schema.h"
#include "io/asset.h"
#include "io/atomic_file.h"
#include "io/gltf_rules.h"

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <malloc.h>

namespace uvpress::cli {

std::unique_ptr<engine::Engine> Globals::make_engine() const {
  auto request = engine::parse_device_request(device);
  if (!request) throw engine::EngineError("--device '" + device + "' is not one of auto, gpu, lavapipe, cpu");
  engine::EngineOptions options;
  options.validation = validation;
  auto e = engine::make_engine(*request, options);
  if (verbose) {
    auto d = e->device();
    std::fprintf(stderr, "device: %s %s (%s)\n", d.backend.c_str(), d.name.c_str(), d.type.c_str());
  }
  return e;
}

io::GltfFile Globals::load_input(const std::string& path, nlohmann::ordered_json* checked) const {
  io::GltfFile file = io::load_gltf(path, refs());
  const std::vector<io::RuleIssue> issues = io::check_rules(file);
  if (checked) *checked = io::validation_json(issues);
  if (issues.empty()) return file;
  // An input the later stages cannot read fails with that reason alone (one error line).
  io::build_asset(file);
  if (strict) throw InputError(path, io::describe_issues(issues) + ": refused (--strict)");
  std::fprintf(stderr, "uvpress: %s: warning: %s; what uvpress does not rewrite keeps them (--strict refuses such inputs)\n",
               path.c_str(), io::describe_issues(issues).c_str());
  return file;
}

void Globals::prepare_outputs(const std::vector<std::string>& files, const std::vector<std::string>& folders) const {
  if (!report.empty()) io::prepare_output_file(report);
  for (const auto& f : files)
    if (!f.empty()) io::prepare_output_file(f);
  for (const auto& d : folders)
    if (!d.empty()) io::prepare_output_folder(d);
}

void Globals::write_report(const nlohmann::ordered_json& report) const {
  io::AtomicWriter writer;
  write_report(report, writer);
  writer.commit();
}

void Globals::write_report(const nlohmann::ordered_json& report, io::AtomicWriter& writer) const {
  if (report.empty() || this->report.empty()) return;
  nlohmann::ordered_json out = {{"schema", kReportSchema}};
  for (const auto& [key, value] : report.items())
    if (key != "schema") out[key] = value;
  writer.add(this->report, out.dump(2) + "\n");
}

void Globals::stage(const char* name, std::chrono::steady_clock::time_point& since) const {
  auto now = std::chrono::steady_clock::now();
  if (verbose) std::fprintf(stderr, "%s: %.1f ms\n", name, std::chrono::duration<double, std::milli>(now - since).count());
  since = now;
}

std::string human_bytes(uint64_t b) {
  char buf[32];
  if (b < 1024) std::snprintf(buf, sizeof buf, "%llu B", (unsigned long long)b);
  else if (b < 1024 * 1024) std::snprintf(buf, sizeof buf, "%.1f KB", b / 1024.0);
  else std::snprintf(buf, sizeof buf, "%.1f MB", b / (1024.0 * 1024.0));
  return buf;
}

}  // namespace uvpress::cli

int main(int argc, char** argv) {
  using namespace uvpress;
  // A file-size limit (ulimit -f, a quota) then fails the write with EFBIG, which the
  // writers turn into one error line, instead of killing the process mid-output.
  std::signal(SIGXFSZ, SIG_IGN);
  // Freed buffers stay in the heap for the next one of their size instead of going back to
  // the kernel: glibc maps every block of 128 KiB and more on its own and unmaps it when
  // freed, so each candidate's images and renders faulted in fresh pages again, on the
  // thread that allocated them. CesiumMilkTruck's reparam at half the texels: 1.8 M -> 0.26 M
  // page faults, 110 -> 92 s, peak RSS +3 % (DEVELOPERS.md, Performance notes).
  mallopt(M_MMAP_THRESHOLD, 1 << 30);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  cli::Globals g;
  if (const char* env = std::getenv("UVPRESS_DEVICE"); env && *env) g.device = env;
  if (const char* env = std::getenv("UVPRESS_VALIDATION"); env && std::string(env) == "1") g.validation = true;

  CLI::App app{"uvpress: re-parameterizes textured glTF assets so that smaller textures look as good on screen"};
  app.set_version_flag("--version", std::string("uvpress ") + UVPRESS_VERSION);
  app.require_subcommand(1);
  app.fallthrough();  // global options may follow the subcommand
  app.add_flag("-v,--verbose", g.verbose, "Print the device and stage timings on stderr");
  app.add_option("--device", g.device, "Compute backend: auto | gpu | lavapipe | cpu (or UVPRESS_DEVICE)")
      ->check(CLI::IsMember({"auto", "gpu", "lavapipe", "cpu"}));
  app.add_option("--report", g.report, "Write a JSON report of the run to this file");
  app.add_flag("--vulkan-validation", g.validation, "Enable the Khronos validation layer (or UVPRESS_VALIDATION=1)");
  app.add_flag("--allow-outside-refs", g.allow_outside_refs,
               "Let buffer and image URIs name files outside the asset's folder (trusted inputs only)");
  app.add_flag("--strict", g.strict,
               "Refuse a glTF input that breaks the Khronos validator's buffer, accessor and mesh rules (default: warn)");
  cli::add_reparam(app, g);
  cli::add_info(app, g);
  cli::add_copy(app, g);
  cli::add_demo(app, g);
  cli::add_bench(app, g);
  cli::add_flatten(app, g);
  cli::add_eval(app, g);
  cli::add_batch(app, g);
  // Global options are parsed before or after the subcommand but listed only by
  // `uvpress --help`: every subcommand's help names them too.
  for (CLI::App* sub : app.get_subcommands({}))
    sub->footer("Global options (before or after the command): -v/--verbose, --report FILE.json, "
                "--device auto|gpu|lavapipe|cpu, --vulkan-validation, --allow-outside-refs, --strict (see uvpress --help)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // The hint names the help of the subcommand the error is in ("uvpress reparam --help").
    std::string hint;
    for (CLI::App* at = &app;;) {
      auto subs = at->get_subcommands();
      if (subs.empty()) break;
      at = subs.back();
      hint += " " + at->get_name();
    }
    std::fprintf(stderr, "uvpress: %s (see uvpress%s --help)\n", e.what(), hint.c_str());
    return 2;
  }
  try {
    if (g.report.size() && uvpress::io::extension_of(g.report) != ".json")
      throw InputError(g.report, "--report must name a .json file");
    return g.action ? g.action() : 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "uvpress: %s: %s\n", e.file().c_str(), e.what());
  } catch (const engine::EngineError& e) {
    std::fprintf(stderr, "uvpress: device: %s\n", e.what());
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "uvpress: out of memory\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uvpress: internal error: %s\n", e.what());
  }
  return 1;
}
