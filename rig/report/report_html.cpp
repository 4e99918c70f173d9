#include "rig/report/report_html.hpp"
#include "rig/report/page_template.hpp"

#include <stdexcept>

#include "rig/report/base64.hpp"

namespace vitreo::report {

namespace assets {
std::string_view chartjs();  // /usr/share/javascript/chart.js/chart.min.js, embedded at build time
std::string_view page();     // report_page.html, embedded at build time
}  // namespace assets

namespace {

std::string html_text(std::string_view s) {
  std::string out;
  for (const char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

}  // namespace

std::string report_html(const PageInputs& in) {
  std::string page(assets::page());
  // Chart.js's minified code never holds "</script" (checked here, so a new version that did could
  // not silently end the script element early).
  if (assets::chartjs().find("</script") != std::string_view::npos) throw std::logic_error("Chart.js holds </script>");
  // The markers are filled in order of the template, each checked to be there once; the JSON's '<'
  // are escaped by the JSON writer, so it cannot close its script element either.
  fill(page, "@GENERATED@", html_text(in.generated));
  fill(page, "@FUNDUS_NAME@", html_text(in.final_png_name.empty() ? "no instructor frame in the session folder" : in.final_png_name));
  fill(page, "@FUNDUS_SRC@", in.final_png.empty() ? std::string() : "data:image/png;base64," + base64_encode(in.final_png));
  std::string moments;
  for (const KeyMomentFrame& m : in.key_moments) {
    moments += "<figure><img class=\"fundus\" alt=\"" + html_text(m.what) + "\" src=\"data:image/png;base64," + base64_encode(m.png) +
               "\"><figcaption>step " + std::to_string(m.step) + ": <b>" + html_text(m.what) + "</b> (" + html_text(m.file) +
               ")</figcaption></figure>";
  }
  if (moments.empty()) moments = "<p class=\"meta\">no pictures of key moments in the session folder (the session rendered no frames, or nothing went wrong and the case did not end)</p>";
  fill(page, "<!--@KEY_MOMENTS@-->", moments);
  fill(page, "@COMPARE_LABEL@", html_text(in.compare_label));
  fill(page, "@COMPARE_FUNDUS_SRC@", in.compare_png.empty() ? std::string() : "data:image/png;base64," + base64_encode(in.compare_png));
  fill(page, "/*@CHARTJS@*/", assets::chartjs());
  fill(page, "/*@COMPARE_JSON@*/", in.compare_json.empty() ? std::string_view("null") : in.compare_json);
  fill(page, "/*@REPORT_JSON@*/", in.report_json);  // last: nothing is searched in the data
  return page;
}

}  // namespace vitreo::report
