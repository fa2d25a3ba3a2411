#include "lcmloc/app/cli.hpp"

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <new>

#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/logging.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/transport.hpp"

namespace lcmloc::app {

namespace {
void addLogLevelOption(CLI::App& app, std::string& level) {
  app.add_option("--log-level", level, "trace, debug, info, warn, error, critical, off")
      ->capture_default_str()
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
}

/// CLI11 checks ranges, but "nan" passes every range check (each comparison with it is false)
/// and "inf" an open one, and an integer beyond its type is clamped: refuses both, for every
/// numeric option of app and its subcommands, naming the option.
void checkNumbers(const CLI::App& app) {
  for (const CLI::Option* o : app.get_options()) {
    const std::string type = o->get_type_name();
    const bool is_float = type.rfind("FLOAT", 0) == 0, is_int = type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0;
    if (!is_float && !is_int) continue;
    for (const std::string& token : o->results()) {  // (split at an option's delimiter already)
      if (token.empty()) continue;
      errno = 0;
      char* end = nullptr;
      if (is_float) {
        const double v = std::strtod(token.c_str(), &end);
        if (end != token.c_str() && !std::isfinite(v))
          throw CLI::ValidationError(o->get_name(), token + " is not a finite number");
      } else {
        if (token[0] == '-')
          (void)std::strtoll(token.c_str(), &end, 10);
        else
          (void)std::strtoull(token.c_str(), &end, 10);
        if (end != token.c_str() && errno == ERANGE)
          throw CLI::ValidationError(o->get_name(), token + " is out of range for an integer");
      }
    }
  }
  for (const CLI::App* sub : app.get_subcommands()) checkNumbers(*sub);
}
}  // namespace

void addCommonOptions(CLI::App& app, CommonOptions& opts) {
  if (opts.config.empty()) opts.config = defaultConfigPath();
  if (opts.lcm_url.empty()) opts.lcm_url = bus::defaultLcmUrl();
  app.add_option("--config", opts.config, "scenario YAML file")->capture_default_str();
  app.add_option("--lcm-url", opts.lcm_url, "LCM provider URL (default: $LCM_DEFAULT_URL or udpm)")
      ->capture_default_str();
  addLogLevelOption(app, opts.log_level);
}

CLI::Option* addOfflineOptions(CLI::App& app, CommonOptions& opts, const std::string& config_help) {
  CLI::Option* config = app.add_option("--config", opts.config, config_help);
  app.add_option("--lcm-url", opts.lcm_url,
                 "accepted for uniformity with the processes on the bus; unused (files only, no LCM networking)");
  addLogLevelOption(app, opts.log_level);
  return config;
}

namespace {
CLI::Validator bound(const char* name, bool (*ok)(double), const char* what) {
  return CLI::Validator(
      [ok, what](std::string& s) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(s, v)) return s + " is not a number";
        return ok(v) ? std::string() : s + " is not " + what;
      },
      name);
}
}  // namespace
CLI::Validator positive() { return bound("POSITIVE", [](double v) { return v > 0.0; }, "> 0"); }
CLI::Validator nonNegative() { return bound("NONNEGATIVE", [](double v) { return v >= 0.0; }, ">= 0"); }
CLI::Validator wallSeconds() {
  return bound("SECONDS", [](double v) { return v >= 0.0 && v <= 86400.0; }, "in [0, 86400] (a day at most)");
}
CLI::Validator seed() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        uint64_t v = 0;
        // strtoull (and so a uint64_t option) takes "-1" as 2^64 - 1
        if (s.empty() || s[0] == '-' || s[0] == '+' || !CLI::detail::lexical_cast(s, v))
          return s + " is not a seed (an integer from 0 to 18446744073709551615)";
        return std::string();
      },
      "SEED");
}

const char* const kExitCodesHelp =
    "Exit status: 0 ok, 1 runtime error, 2 usage or configuration error (also a missing input file, or an "
    "existing output without --overwrite), 3 damaged input (the work is done with its intact part).";

std::string version() { return LCMLOC_VERSION; }

CLI::Option* addOutputOption(CLI::App& app, std::string& path, const std::string& help) {
  return app.add_option("-o,--output", path, help);
}

CLI::Option* addOverwriteFlag(CLI::App& app, bool& overwrite) {
  return app.add_flag("--overwrite", overwrite,
                      "replace an existing output (a file, or the files in a directory that is not empty); "
                      "without it an existing output is refused (exit 2)");
}

namespace {
void addExitCodesFooter(CLI::App& app) {
  const std::string own = app.get_footer();
  app.footer(own.empty() ? std::string(kExitCodesHelp) : own + "\n" + kExitCodesHelp);
  for (CLI::App* sub : app.get_subcommands({})) addExitCodesFooter(*sub);
}
}  // namespace

int runProcess(CLI::App& app, int argc, char** argv, const CommonOptions& opts,
               const std::string& process_name, const std::function<int()>& body) {
  app.set_version_flag("--version", process_name + " " + version(), "print the program's name and version, and exit");
  addExitCodesFooter(app);
  try {
    app.parse(argc, argv);
    checkNumbers(app);
  } catch (const CLI::ParseError& e) {
    // --help / --version exit 0; any other command-line error is a configuration error
    // (exit 2, as a bad config file), with CLI11's message.
    return app.exit(e) == 0 ? kExitOk : kExitConfigError;
  }
  setupLogging(process_name, opts.log_level);
  installSignalHandlers();
  try {
    return body();
  } catch (const ConfigError& e) {
    spdlog::error("configuration error: {}", e.what());
    return kExitConfigError;
  } catch (const UsageError& e) {
    spdlog::error("{}", e.what());
    return kExitUsageError;
  } catch (const CLI::Error& e) {  // an argument found bad after parsing (e.g. lcmloc-ctl's --param)
    spdlog::error("{}", e.what());
    return kExitConfigError;
  } catch (const std::bad_alloc&) {
    spdlog::error("out of memory: the run asks for more than this machine has (a very long duration, a huge input?)");
    return kExitRuntimeError;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kExitRuntimeError;
  }
}

}  // namespace lcmloc::app
