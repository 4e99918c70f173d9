#include "rig/session/calibration_in_force.hpp"

#include <cstdio>
#include <stdexcept>

#include "rig/files/read_text_file.hpp"

namespace vitreo::rig {

calibration::CalibrationFile apply_calibration(const std::string& text, const std::string& origin, ModelConfig& model) {
  const calibration::CalibrationFile c = calibration::parse_calibration(text, origin);
  ModelConfig out = model;
  out.calibration = {};
  out.measured_ports = {};
  for (std::size_t i = 0; i < out.calibration.size(); ++i) {
    TrackerCalibration& t = out.calibration[i];
    if (c.registration) {
      t.rig_to_eye = c.registration->rig_to_eye;
      t.eye_center_in_rig_mm = c.registration->eye_center_in_rig_mm;
    }
    if (const calibration::InstrumentRecord* r = c.instrument(static_cast<int>(i))) t.tip_offset_mm = r->tip_offset_mm;
    if (const calibration::PortRecord* p = c.port(static_cast<int>(i))) out.measured_ports[i] = Port{p->position_mm, p->outward};
  }
  out.eye_zero = c.eye_zero ? c.eye_zero->zero : core::Quat::Identity();
  out.pedals.axis_ranges.clear();
  for (const calibration::PedalRecord& p : c.pedals) {
    AxisRange r = p.range;
    r.pedal_id = p.pedal;
    r.axis = p.axis;
    out.pedals.axis_ranges.push_back(r);
  }
  out.calibration_text = text;
  model = std::move(out);
  return c;
}

std::string calibration_id(const calibration::CalibrationFile& c) {
  return calibration::utc_timestamp(c.created_unix_s) + " " + c.tool;
}

CalibrationLoad load_calibration(const std::string& path, std::vector<DeviceSpec>& devices, ModelConfig& model,
                                 double max_age_days, std::int64_t now_unix_s) {
  const files::TextFile f = files::read_text_file(path);
  if (!f.text) throw std::runtime_error("calibration " + path + ": " + f.error);
  CalibrationLoad load;
  ModelConfig candidate = model;
  load.file = apply_calibration(*f.text, path, candidate);
  std::vector<calibration::DeviceSerial> rig;
  std::vector<DeviceSpec> pinned = devices;
  const std::string id = calibration_id(load.file);
  for (DeviceSpec& d : pinned) {
    std::uint32_t serial = d.expected_serial;
    for (const calibration::DeviceSerial& s : load.file.devices) {
      if (s.name != d.name) continue;
      d.calibration = id;
      if (serial == 0) {
        serial = d.expected_serial = s.serial;
        load.notes.push_back(d.name + " must announce serial " + std::to_string(s.serial) + " (the calibrated unit)");
      }
    }
    rig.push_back({d.name, serial});
  }
  if (const std::string other = calibration::check_devices(load.file, rig); !other.empty())
    throw std::runtime_error("calibration " + path + " is for other devices: " + other + "; recalibrate this rig (vitreo-calibrate)");
  if (auto stale = calibration::age_warning(load.file, now_unix_s, max_age_days)) load.warnings.push_back(*stale);
  load.notes.push_back("calibration in force: " + path + " (" + calibration_id(load.file) + ")");
  if (load.file.registration) {
    char b[200];
    std::snprintf(b, sizeof b, "tracker registration: %zu fiducials, FRE %.3f mm, TRE %.3f mm", load.file.registration->fiducials,
                  load.file.registration->fre_mm, load.file.registration->tre_mm);
    load.notes.emplace_back(b);
  }
  if (load.file.eyepieces) {
    const calibration::EyepieceRecord& e = *load.file.eyepieces;
    char b[240];
    std::snprintf(b, sizeof b, "eyepiece displays: left image shifted (%.1f, %.1f) px, right (%.1f, %.1f) px; stereo base %.1f mm, convergence %s",
                  e.offset_px[0][0], e.offset_px[0][1], e.offset_px[1][0], e.offset_px[1][1], e.stereo_base_mm,
                  e.convergence_mm > 0 ? (std::to_string(static_cast<int>(std::lround(e.convergence_mm))) + " mm").c_str() : "at the working plane");
    load.notes.emplace_back(b);
  }
  devices = std::move(pinned);
  model = std::move(candidate);
  return load;
}

render::EyepieceSettings eyepiece_settings(const calibration::EyepieceRecord& e) {
  render::EyepieceSettings out;
  for (int eye = 0; eye < 2; ++eye)
    out.offset_px[static_cast<std::size_t>(eye)] = {static_cast<float>(e.offset_px[eye][0]), static_cast<float>(e.offset_px[eye][1])};
  out.stereo_base_mm = static_cast<float>(e.stereo_base_mm);
  out.convergence_mm = static_cast<float>(e.convergence_mm);
  return out;
}

}  // namespace vitreo::rig
