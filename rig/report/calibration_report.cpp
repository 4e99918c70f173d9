#include "rig/report/calibration_report.hpp"

#include <numbers>
#include <stdexcept>
#include <vector>

#include "rig/calibration/calibration_file.hpp"
#include "rig/files/write_file_atomically.hpp"
#include "rig/report/json_writer.hpp"
#include "rig/report/page_template.hpp"

namespace vitreo::report {

namespace assets {
std::string_view chartjs();           // Chart.js, embedded at build time
std::string_view calibration_page();  // calibration_page.html, embedded at build time
}  // namespace assets

namespace {

namespace cal = rig::calibration;

void array(JsonWriter& j, const std::vector<double>& v) {
  j.begin_array();
  for (double x : v) j.value(x);
  j.end_array();
}

void vec3(JsonWriter& j, const core::Vec3& v) {
  j.begin_array();
  j.value(v.x()).value(v.y()).value(v.z());
  j.end_array();
}

}  // namespace

std::string calibration_report_json(const CalibrationReportInputs& in) {
  if (!in.analysis) throw std::invalid_argument("calibration_report_json: no analysis");
  const cal::Analysis& a = *in.analysis;
  const cal::CalibrationFile& f = a.file;
  const cal::Limits& lim = a.limits;
  JsonWriter j;
  j.begin_object();
  j.key("report_format").value(kCalibrationReportFormat);
  j.key("rig").value(f.rig);
  j.key("tool").value(f.tool);
  j.key("created_utc").value(cal::utc_timestamp(f.created_unix_s));
  j.key("result").value(a.ok ? "PASS" : "FAIL");
  j.key("calibration_file");
  if (in.calibration_file.empty()) j.value(nullptr);
  else j.value(in.calibration_file);
  j.key("errors").begin_array();
  for (const std::string& e : a.errors) j.value(e);
  j.end_array();
  j.key("devices").begin_array();
  for (const cal::DeviceSerial& d : f.devices) {
    j.begin_object();
    j.key("name").value(d.name);
    j.key("serial").value(static_cast<std::int64_t>(d.serial));
    j.end_object();
  }
  j.end_array();
  j.key("steps").begin_array();
  for (const cal::StepOutcome& o : a.steps) {
    j.begin_object();
    j.key("device").value(o.step ? o.step->device : "");
    j.key("instruction").value(o.step ? o.step->instruction : "");
    j.key("ok").value(o.ok);
    j.key("feedback").value(o.feedback);
    j.end_object();
  }
  j.end_array();

  j.key("pivots").begin_array();
  for (const cal::PivotPlot& p : a.pivots) {
    j.begin_object();
    j.key("device").value(p.device);
    j.key("instrument").value(p.instrument);
    j.key("ok").value(p.ok);
    const cal::InstrumentRecord* rec = p.ok ? f.instrument(p.instrument) : nullptr;
    j.key("tip_offset_mm");
    if (rec) vec3(j, rec->tip_offset_mm);
    else j.value(nullptr);
    j.field("rms", p.rms_mm, "mm");
    j.field("max_rms", lim.pivot.max_rms_mm, "mm");
    j.field("spread", p.spread_deg, "deg");
    j.field("min_spread", lim.pivot.min_spread_deg, "deg");
    j.key("residuals_mm");
    array(j, p.residuals_mm);
    j.key("tilt_x_deg");
    array(j, p.tilt_x_deg);
    j.key("tilt_y_deg");
    array(j, p.tilt_y_deg);
    j.end_object();
  }
  j.end_array();

  j.key("registration");
  if (!a.fiducial_residuals_mm.empty() || f.registration) {
    j.begin_object();
    j.key("residuals_mm");
    array(j, a.fiducial_residuals_mm);
    j.field("max_fre", lim.registration.max_fre_mm, "mm");
    if (f.registration) {
      j.key("fiducials").value(static_cast<std::int64_t>(f.registration->fiducials));
      j.field("fre", f.registration->fre_mm, "mm");
      j.field("tre", f.registration->tre_mm, "mm");
      j.key("tre_measured").value(f.registration->tre_measured);
    }
    j.end_object();
  } else {
    j.value(nullptr);
  }
  j.key("ports").begin_array();
  for (const cal::PortRecord& p : f.ports) {
    j.begin_object();
    j.key("port").value(p.port);
    j.key("position_mm");
    vec3(j, p.position_mm);
    j.field("spread", p.spread_mm, "mm");
    j.field("max_spread", lim.port.max_spread_mm, "mm");
    j.end_object();
  }
  j.end_array();
  j.key("pedals").begin_array();
  for (const cal::PedalRecord& p : f.pedals) {
    j.begin_object();
    j.key("pedal").value(p.pedal);
    j.key("axis").value(p.axis);
    j.key("lo").value(p.range.lo);
    j.key("hi").value(p.range.hi);
    j.key("dead_zone").value(p.range.dead_zone);
    j.end_object();
  }
  j.end_array();
  j.key("eye_zero");
  if (f.eye_zero) {
    j.begin_object();
    j.field("angle", Eigen::AngleAxisd(f.eye_zero->zero).angle() * 180.0 / std::numbers::pi, "deg");
    j.field("spread", f.eye_zero->spread_deg, "deg");
    j.key("samples").value(static_cast<std::int64_t>(f.eye_zero->samples));
    j.end_object();
  } else {
    j.value(nullptr);
  }
  j.key("clocks").begin_array();
  for (const cal::ClockRecord& c : f.clocks) {
    j.begin_object();
    j.key("device").value(c.device);
    j.field("offset", c.offset_ms, "ms");
    j.field("drift", c.drift_ppm, "ppm");
    j.field("latency", c.latency_ms, "ms");
    j.field("rms", c.rms_ms, "ms");
    j.end_object();
  }
  j.end_array();
  j.key("summary_text").value(cal::summary_text(a));
  j.end_object();
  return j.take();
}

std::string calibration_report_html(const CalibrationReportInputs& in) {
  std::string page(assets::calibration_page());
  if (assets::chartjs().find("</script") != std::string_view::npos) throw std::logic_error("Chart.js holds </script>");
  std::string generated;
  for (const char c : in.generated) {
    if (c == '<') generated += "&lt;";
    else if (c == '&') generated += "&amp;";
    else generated += c;
  }
  fill(page, "@GENERATED@", generated);
  fill(page, "/*@CHARTJS@*/", assets::chartjs());
  fill(page, "/*@CALIBRATION_JSON@*/", calibration_report_json(in));  // last: nothing is searched in the data
  return page;
}

WrittenCalibrationReport write_calibration_report(const std::string& base, const CalibrationReportInputs& in) {
  WrittenCalibrationReport w{base + ".report.json", base + ".report.html"};
  for (const auto& [path, text] : {std::pair{w.json_path, calibration_report_json(in)}, std::pair{w.html_path, calibration_report_html(in)}}) {
    if (const std::string why = files::write_file_atomically(path, text); !why.empty()) throw std::runtime_error(path + ": " + why);
  }
  return w;
}

}  // namespace vitreo::report
