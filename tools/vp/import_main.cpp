// lcmloc-import-vp: Victoria Park CSV files (odometry + GPS) -> an LCM log of lcmloc types.

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/vp/vp.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{
      "lcmloc-import-vp: imports the Victoria Park data set (vp_odometry.csv: time_ms, speed_mps, steering_rad; "
      "vp_gps.csv: time_ms, Lo_m, La_m) into an LCM log: ODOMETRY (delta_s of the rear axle centre after the "
      "encoder offset correction, steering, delta_theta by eq. 2), GPS (lat/lon about the config's datum) and "
      "every k-th fix on GPS_HELDOUT (not used by the filters). Refused rows are listed with their line numbers."};
  app::CommonOptions opts;
  opts.config = app::configDir() + "/victoria_park.yaml";
  app::addCommonOptions(app, opts);
  vp::ImportOptions io;
  std::string dir;
  int show = 20;
  app.add_option("--dir", dir, "data directory holding vp_odometry.csv and vp_gps.csv");
  app.add_option("--odometry", io.odometry_csv, "odometry CSV (overrides --dir)");
  app.add_option("--gps", io.gps_csv, "GPS CSV (overrides --dir)");
  bool overwrite = false;
  app::addOutputOption(app, io.output, "output LCM log")->required();
  app::addOverwriteFlag(app, overwrite);
  app.add_option("--wheelbase", io.wheelbase, "L [m]")->capture_default_str()->check(lcmloc::app::positive());
  app.add_option("--encoder-offset", io.encoder_offset,
                 "H: speed encoder left of the rear axle centre [m], at most half a vehicle's track")
      ->capture_default_str()->check(CLI::Range(vp::kEncoderOffset.lo, vp::kEncoderOffset.hi));
  app.add_option("--holdout-every", io.holdout_every, "hold every k-th fix out on GPS_HELDOUT (0 = none)")
      ->capture_default_str()->check(lcmloc::app::nonNegative());
  app.add_option("--holdout-phase", io.holdout_phase, "fix i is held out when i % k == phase, phase in [0, k)")
      ->capture_default_str();
  app.add_option("--heldout-channel", io.heldout_channel,
                 "channel of the held-out fixes (not the config's odometry or GPS channel)")->capture_default_str();
  app.add_option("--gps-std", io.gps_std, "position_std written into the fixes [m] (0 = the filter's gnss.gps_std)")
      ->capture_default_str()->check(lcmloc::app::nonNegative());
  app.add_option("--max-rows", io.max_rows, "a slice: the first N odometry rows and the GPS rows of their time span (0 = all)")
      ->capture_default_str()->check(lcmloc::app::nonNegative());
  app.add_option("--show-refused", show, "list at most this many refused rows")
      ->capture_default_str()
      ->check(lcmloc::app::nonNegative());
  app.footer("The datum (lat/lon of the local frame's origin) and the channel names come from --config.");

  return app::runProcess(app, argc, argv, opts, "lcmloc-import-vp", [&]() -> int {
    return vp::importCommand(app::loadSystemConfig(opts.config), io, dir, show, overwrite);
  });
}
