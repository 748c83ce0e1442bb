#include "pyrocam/simulation/simulator.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

#include "detail/portable_math.h"
#include "detail/random.h"
#include "detail/two_halves.h"
#include "pyrocam/core/dataset.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/core/noise_model.h"

namespace pyrocam {
namespace {

constexpr double kTableStartC = 100.0;  // below this nothing glows visibly to these cameras
constexpr double kTableStopC = 4200.0;

}  // namespace

Simulator::Simulator(CameraProfile profile, Eigen::MatrixXd system_qe, std::uint64_t noise_seed)
    : profile_(std::move(profile)), system_qe_(std::move(system_qe)), seed_(noise_seed) {
  if (system_qe_.rows() != profile_.band_count() || system_qe_.cols() != profile_.grid.size())
    throw InputError("simulator: system QE shape does not match the profile " + profile_.name);
  const int n = static_cast<int>(kTableStopC - kTableStartC) + 1;
  rate_table_.resize(profile_.band_count(), n);
  // Built when a simulated camera starts: half of it on another core.
  detail::in_two_halves(n, 512, [&](int from, int to) {
    for (int i = from; i < to; ++i)
      rate_table_.col(i) =
          electron_rates(profile_, system_qe_, celsius_to_kelvin(kTableStartC + i));
  });
}

double Simulator::electron_rate(int band, double temperature_c) const {
  if (!(temperature_c >= kTableStartC)) return 0.0;
  const double pos = std::min(temperature_c, kTableStopC) - kTableStartC;
  const auto i0 = static_cast<Eigen::Index>(pos);
  const auto i1 = std::min<Eigen::Index>(i0 + 1, rate_table_.cols() - 1);
  const double f = pos - static_cast<double>(i0);
  // Rates span many decades: interpolate the logarithm.
  const double r0 = rate_table_(band, i0), r1 = rate_table_(band, i1);
  if (r0 <= 0 || r1 <= 0) return r0 * (1 - f) + r1 * f;
  return r0 * portable::pow(r1 / r0, f);
}

Eigen::VectorXd Simulator::mean_signal_dn(double temperature_c, double exposure_us,
                                          double emissivity) const {
  Eigen::VectorXd s(profile_.band_count());
  for (int b = 0; b < profile_.band_count(); ++b)
    s[b] = electron_rate(b, temperature_c) * exposure_us * 1e-6 * emissivity *
           profile_.dn_per_electron()[b];
  return s;
}

double Simulator::exposure_for(double temperature_c, double target_dn, double emissivity) const {
  const double per_us = mean_signal_dn(temperature_c, 1.0, emissivity).maxCoeff();
  if (!(per_us > 0))
    throw InputError("simulator: no signal at " + std::to_string(temperature_c) + " degC");
  return target_dn / per_us;
}

void Simulator::ensure_pixel_maps(int width, int height) {
  if (dark_fpn_.cols == width && dark_fpn_.rows == height) return;
  Random rng(mix(seed_ ^ 0xF1F0ull));
  const auto normal = [](Random& r) { return static_cast<float>(r.normal()); };
  dark_fpn_.create(height, width, CV_32F);
  prnu_.create(height, width, CV_32F);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      dark_fpn_.at<float>(y, x) = static_cast<float>(profile_.noise.dark_fpn_dn) * normal(rng);
      prnu_.at<float>(y, x) = 1.f + static_cast<float>(profile_.noise.prnu) * normal(rng);
    }
}

cv::Mat Simulator::render(const cv::Mat& temperature_c, double exposure_us, double emissivity,
                          double gain_db) {
  if (temperature_c.type() != CV_32F) throw InputError("simulator: temperature map must be CV_32F");
  if (!std::isfinite(gain_db)) throw InputError("simulator: the gain must be a number of dB");
  const double gain = analogue_gain_factor(gain_db);
  const int width = temperature_c.cols, height = temperature_c.rows;
  ensure_pixel_maps(width, height);
  const int type = profile_.bit_depth == 8 ? CV_8U : CV_16U;
  cv::Mat out(height, width, type);
  const NoiseModel& nm = profile_.noise;
  const Eigen::VectorXd k = profile_.dn_per_electron();
  const double t_s = exposure_us * 1e-6;
  const double max_dn = profile_.max_dn();
  const std::uint64_t frame_seed = mix(seed_ + 0x1000003ull * ++frame_counter_);
  constexpr int kStripe = 16;  // fixed stripes keep the noise independent of thread count

  cv::parallel_for_(cv::Range(0, (height + kStripe - 1) / kStripe), [&](const cv::Range& r) {
    for (int s = r.start; s < r.end; ++s) {
      Random rng(mix(frame_seed ^ static_cast<std::uint64_t>(s)));
      const auto normal = [](Random& r) { return r.normal(); };
      // Scenes are mostly uniform regions: the last rate of each band is usually the next one.
      std::vector<float> last_t(static_cast<std::size_t>(profile_.band_count()), NAN);
      std::vector<double> last_rate(last_t.size(), 0.0);
      for (int y = s * kStripe; y < std::min(height, (s + 1) * kStripe); ++y) {
        const float* t_row = temperature_c.ptr<float>(y);
        const float* fpn_row = dark_fpn_.ptr<float>(y);
        const float* prnu_row = prnu_.ptr<float>(y);
        for (int x = 0; x < width; ++x) {
          const int band = profile_.mosaic.band_at(x, y);
          const auto b = static_cast<std::size_t>(band);
          if (!(t_row[x] == last_t[b])) {
            last_t[b] = t_row[x];
            last_rate[b] = electron_rate(band, t_row[x]);
          }
          const double mean_e =
              last_rate[b] * t_s * emissivity * prnu_row[x] + nm.dark_current_e_per_s * t_s;
          double e = mean_e;
          if (noise_) {
            if (mean_e < 30) {
              e = static_cast<double>(rng.poisson(mean_e));
            } else {
              e = mean_e + std::sqrt(mean_e) * normal(rng);
            }
          }
          // The gain amplifies the collected charge; the read noise comes after it.
          e = gain * std::clamp(e, 0.0, nm.full_well_e);
          if (noise_) e += nm.read_noise_e * normal(rng);
          // A clamped black level takes the dark current's mean out (its noise stays).
          const double clamped_dn =
              black_level_clamp_ ? k[band] * gain * nm.dark_current_e_per_s * t_s : 0.0;
          const double dn = std::clamp(std::round(k[band] * e + profile_.dark_offset_dn +
                                                  black_level_shift_dn_ + fpn_row[x] - clamped_dn),
                                       0.0, max_dn);
          if (type == CV_8U)
            out.ptr<std::uint8_t>(y)[x] = static_cast<std::uint8_t>(dn);
          else
            out.ptr<std::uint16_t>(y)[x] = static_cast<std::uint16_t>(dn);
        }
      }
    }
  });
  return out;
}

cv::Mat Simulator::render_dark(int width, int height, double exposure_us) {
  return render(cv::Mat(height, width, CV_32F, cv::Scalar(0.f)), exposure_us);
}

namespace {

// A reference source of a campaign (CampaignSettings::reference_temperatures_c) as drawn.
struct ReferencePlan {
  double nominal_c = 0, true_c = 0, scale = 1;
  std::vector<double> exposures;
  std::vector<bool> new_dark;  // per exposure: no earlier sweep has a dark of it
};

// The references' own random stream, so that the furnace's part of the dataset is the same with
// references or without (their frames are also rendered after the furnace's).
template <typename Sweep>
std::vector<ReferencePlan> plan_references(const CampaignSettings& s, const Simulator& camera,
                                           const std::vector<double>& furnace_exposures,
                                           const Sweep& sweep) {
  Random rng(mix(s.reference_seed ^ 0x8EFE8E4CEull));
  const auto scale_draw = [](Random& r) { return r.uniform(0.05, 0.5); };
  const auto error_draw = [](Random& r) { return r.normal(); };
  std::vector<double> dark_exposures = furnace_exposures;
  std::vector<ReferencePlan> plans;
  for (double t : s.reference_temperatures_c) {
    ReferencePlan p;
    p.nominal_c = t;
    p.scale = scale_draw(rng);
    p.true_c = t + s.reference_uncertainty_c * error_draw(rng);
    // The operator sees the source's brightness, not its scale and true temperature apart.
    p.exposures = sweep(
        camera.exposure_for(t, 0.5 * camera.profile().thresholds.calibration_dim_dn, p.scale));
    for (double e : p.exposures) {
      const bool seen = std::any_of(dark_exposures.begin(), dark_exposures.end(),
                                    [&](double d) { return same_exposure(d, e); });
      p.new_dark.push_back(!seen);
      if (!seen) dark_exposures.push_back(e);
    }
    plans.push_back(std::move(p));
  }
  return plans;
}

}  // namespace

void write_furnace_campaign(const std::filesystem::path& folder, Simulator& camera,
                            CampaignSettings s, const Progress& progress) {
  const bool colour = camera.profile().mosaic.kind == MosaicLayout::Kind::kBayer;
  if (s.temperatures_c.empty())
    for (double t = colour ? 700 : 800; t <= 1100 + 1e-9; t += 10) s.temperatures_c.push_back(t);
  if (s.first_exposure_us <= 0) s.first_exposure_us = colour ? 100 : 10000;
  if (s.exposure_count < 1 || s.frames_per_setting < 1 || s.width < 8 || s.height < 8)
    throw InputError("campaign: needs at least one exposure and frame, and 8x8 pixels");
  // A camera's exposure ends somewhere: 1e8 us, as the first exposure's range says (factor 10
  // and 200 exposures made 1e201 us, and the frames a camera that does not exist).
  const double longest_us = s.first_exposure_us * std::pow(s.exposure_factor, s.exposure_count - 1);
  if (!(longest_us <= 1e8)) {
    std::ostringstream m;
    m << "campaign: the longest exposure, " << s.first_exposure_us << " us x " << s.exposure_factor
      << "^" << s.exposure_count - 1 << " = " << longest_us
      << " us, is past 1e8 us: fewer exposures or a smaller factor";
    throw InputError(m.str());
  }
  if (!std::isfinite(s.black_level_drift_dn))
    throw InputError("campaign: the black level drift must be a number of DN");
  if (!s.reference_temperatures_c.empty() &&
      !(s.reference_uncertainty_c > 0 && std::isfinite(s.reference_uncertainty_c)))
    throw InputError("campaign: the reference temperature uncertainty must be a number > 0 degC");
  camera.profile().mosaic.check_whole_periods(s.width, s.height, "campaign frame size");
  // Files are named by the whole degrees: two sources in one name would overwrite each other.
  for (const std::vector<double>* list : {&s.temperatures_c, &s.reference_temperatures_c}) {
    std::set<long> seen;
    for (double t : *list)
      if (!seen.insert(std::lround(t)).second)
        throw InputError("campaign: two " +
                         std::string(list == &s.temperatures_c ? "furnace temperatures"
                                                               : "reference temperatures") +
                         " round to " + std::to_string(std::lround(t)) +
                         " degC, the whole degrees its files are named by; give each once");
  }
  // Checked before anything is written, so a refused campaign leaves no folders behind.
  const double aspect = 1.2;  // a plate seen at an angle
  const double ry = std::sqrt(s.roi_area_px / (M_PI * aspect)), rx = aspect * ry;
  if (!(s.roi_area_px > 0) || rx > 0.48 * s.width || ry > 0.48 * s.height) {
    const double ry_max = std::min(0.48 * s.height, 0.48 * s.width / aspect);
    std::ostringstream m;
    m << "campaign: an ROI of " << s.roi_area_px << " px (--roi-area) does not fit a " << s.width
      << "x" << s.height << " frame: it takes from 1 to "
      << std::floor(M_PI * aspect * ry_max * ry_max) << " px there";
    throw InputError(m.str());
  }
  std::filesystem::create_directories(folder / "frames");
  std::filesystem::create_directories(folder / "darks");
  if (!s.reference_temperatures_c.empty())
    std::filesystem::create_directories(folder / "references");

  const auto sweep = [&s](double first_us) {
    std::vector<double> e;
    for (int k = 0; k < s.exposure_count; ++k)
      e.push_back(
          std::max(1e-3, std::round(first_us * portable::pow(s.exposure_factor, k) * 1000) / 1000));
    return e;
  };
  const std::vector<double> exposures = sweep(s.first_exposure_us);

  cv::Mat roi = cv::Mat::zeros(s.height, s.width, CV_8U);
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      const double dx = (x + 0.5 - s.width / 2.0) / rx, dy = (y + 0.5 - s.height / 2.0) / ry;
      if (dx * dx + dy * dy <= 1) roi.at<std::uint8_t>(y, x) = 255;
    }
  write_raw_image(folder / "roi.png", roi);

  const std::vector<ReferencePlan> references = plan_references(s, camera, exposures, sweep);
  std::vector<ManifestRow> rows;
  std::size_t settings = (s.temperatures_c.size() + 1) * exposures.size();
  for (const auto& r : references)
    settings += r.exposures.size() +
                static_cast<std::size_t>(std::count(r.new_dark.begin(), r.new_dark.end(), true));
  const std::size_t total = settings * static_cast<std::size_t>(s.frames_per_setting);
  std::size_t done = 0;
  auto emit = [&](const std::string& rel, const cv::Mat& img, FrameKind kind, double t, double e,
                  double u = NAN) {
    write_raw_image(folder / rel, img);
    rows.push_back({rel, kind, t, e, u});
    if (progress) progress(++done, total);
  };
  auto name = [&](const char* dir, const std::string& stem, std::size_t k, int f) {
    std::ostringstream n;
    n << dir << "/" << stem << "e" << std::setw(2) << std::setfill('0') << k << "_f" << f
      << s.image_extension;
    return n.str();
  };
  for (std::size_t k = 0; k < exposures.size(); ++k)
    for (int f = 0; f < s.frames_per_setting; ++f)
      emit(name("darks", "", k, f),
           camera.render(cv::Mat(s.height, s.width, CV_32F, cv::Scalar(s.dark_temperature_c)),
                         exposures[k]),
           FrameKind::kDark, s.dark_temperature_c, exposures[k]);
  Random furnace_rng(mix(s.furnace_seed));
  const auto furnace_error = [](Random& r) { return r.normal(); };
  std::ofstream truth(folder / "furnace-truth.csv");
  truth << "nominal_c,true_c\n" << std::setprecision(10);
  for (std::size_t step = 0; step < s.temperatures_c.size(); ++step) {
    const double t = s.temperatures_c[step];
    if (s.black_level_drift_dn != 0)
      camera.set_black_level_shift(s.black_level_drift_dn * static_cast<double>(step) /
                                   std::max<double>(1, s.temperatures_c.size() - 1));
    const double true_c = t + s.furnace_error_sigma_c * furnace_error(furnace_rng);
    truth << t << "," << true_c << "\n";
    const cv::Mat plate(s.height, s.width, CV_32F, cv::Scalar(static_cast<float>(true_c)));
    std::ostringstream stem;
    stem << "T" << std::setw(4) << std::setfill('0') << std::lround(t) << "_";
    for (std::size_t k = 0; k < exposures.size(); ++k)
      for (int f = 0; f < s.frames_per_setting; ++f)
        emit(name("frames", stem.str(), k, f), camera.render(plate, exposures[k]),
             FrameKind::kFrame, t, exposures[k]);
  }
  camera.set_black_level_shift(0);
  for (const ReferencePlan& r : references) {
    truth << r.nominal_c << "," << r.true_c << "\n";
    std::ostringstream stem;
    stem << "R" << std::setw(4) << std::setfill('0') << std::lround(r.nominal_c) << "_";
    for (std::size_t k = 0; k < r.exposures.size(); ++k)
      for (int f = 0; r.new_dark[k] && f < s.frames_per_setting; ++f)
        emit(name("darks", stem.str(), k, f),
             camera.render(cv::Mat(s.height, s.width, CV_32F, cv::Scalar(s.dark_temperature_c)),
                           r.exposures[k]),
             FrameKind::kDark, s.dark_temperature_c, r.exposures[k]);
    const cv::Mat source(s.height, s.width, CV_32F, cv::Scalar(static_cast<float>(r.true_c)));
    for (std::size_t k = 0; k < r.exposures.size(); ++k)
      for (int f = 0; f < s.frames_per_setting; ++f)
        emit(name("references", stem.str(), k, f), camera.render(source, r.exposures[k], r.scale),
             FrameKind::kReference, r.nominal_c, r.exposures[k], s.reference_uncertainty_c);
  }
  if (!truth) throw InputError((folder / "furnace-truth.csv").string() + ": cannot write");
  write_manifest(folder / "manifest.csv", rows);
  write_mosaic_pattern(folder, camera.profile().mosaic.pattern);
}

}  // namespace pyrocam
