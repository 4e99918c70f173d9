#include "rig/report/survey.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace vitreo::report {

namespace {

using nlohmann::json;

// Band of each page on the modified Cooper-Harper scale: its best rating; the five levels step by
// half a rating towards the worst (errors: 7..9, workload: 4..6, easy: 1..3).
double band_start(const std::string& page) {
  if (page == "easy") return 1.0;
  if (page == "workload") return 4.0;
  return 7.0;  // errors
}

const std::vector<std::string> kInstrumentRatings = {"excellent", "very_good", "good", "fair", "poor"};
const std::vector<std::string> kCategories = {"image_quality", "modeling_detail", "tracking", "physical_interface",
                                              "instrumentation", "other"};

const json& field(const json& j, const char* name) {
  if (!j.contains(name)) throw std::runtime_error(std::string("survey: '") + name + "' is missing");
  return j.at(name);
}

std::string text(const json& j, const char* name, bool required) {
  if (!j.contains(name)) {
    if (required) throw std::runtime_error(std::string("survey: '") + name + "' is missing");
    return "";
  }
  if (!j.at(name).is_string()) throw std::runtime_error(std::string("survey: '") + name + "' must be text");
  const std::string s = j.at(name).get<std::string>();
  if (s.size() > 4000) throw std::runtime_error(std::string("survey: '") + name + "' is longer than 4000 characters");
  return s;
}

bool yes_no(const json& j, const char* name) {
  const json& v = field(j, name);
  if (!v.is_boolean()) throw std::runtime_error(std::string("survey: '") + name + "' must be true or false");
  return v.get<bool>();
}

std::string one_of(const std::string& value, const std::vector<std::string>& allowed, const std::string& what) {
  if (std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    throw std::runtime_error("survey: " + what + " '" + value + "' is not one of " + list);
  }
  return value;
}

}  // namespace

const std::vector<std::string>& survey_levels(const std::string& page) {
  static const std::vector<std::string> errors = {"low", "somewhat_medium", "medium", "somewhat_high", "high"};
  static const std::vector<std::string> easy = {"very_easy", "somewhat_easy", "easy", "somewhat_fair", "fair"};
  return page == "easy" ? easy : errors;  // the workload page uses the error page's words
}

Survey parse_survey(const std::string& json_text) {
  json j;
  try {
    j = json::parse(json_text);
  } catch (const json::parse_error& e) {
    throw std::runtime_error(std::string("survey: not JSON: ") + e.what());
  }
  if (!j.is_object()) throw std::runtime_error("survey: the file must hold one JSON object");
  if (text(j, "format", true) != kSurveyFormat)
    throw std::runtime_error(std::string("survey: 'format' must be \"") + kSurveyFormat + "\"");
  Survey s;
  s.subject = text(j, "subject", false);
  s.date = text(j, "date", false);
  s.comments = text(j, "comments", false);
  s.accomplished = yes_no(j, "accomplished");
  if (s.accomplished) {
    s.errors_small = yes_no(j, "errors_small");
    if (*s.errors_small) {
      s.workload_acceptable = yes_no(j, "workload_acceptable");
      s.page = *s.workload_acceptable ? "easy" : "workload";
    } else {
      s.page = "errors";
    }
    const auto& levels = survey_levels(s.page);
    s.level = one_of(text(j, "level", true), levels, "level");
    const auto at = std::find(levels.begin(), levels.end(), s.level) - levels.begin();
    s.rating = band_start(s.page) + 0.5 * static_cast<double>(at);
    if (j.contains("categories")) {
      const json& c = j.at("categories");
      if (!c.is_object()) throw std::runtime_error("survey: 'categories' must be an object");
      for (const auto& [name, v] : c.items()) {
        one_of(name, kCategories, "category");
        if (!v.is_string()) throw std::runtime_error("survey: category '" + name + "' must be a level");
        s.categories[name] = one_of(v.get<std::string>(), levels, "level of " + name);
      }
    }
  }
  if (j.contains("instruments")) {
    const json& ins = j.at("instruments");
    if (!ins.is_object()) throw std::runtime_error("survey: 'instruments' must be an object");
    for (const auto& [name, v] : ins.items()) {
      if (name.empty() || name.size() > 40) throw std::runtime_error("survey: an instrument's name must be 1-40 characters");
      if (!v.is_object()) throw std::runtime_error("survey: instrument '" + name + "' must be {rating, comment}");
      InstrumentRating r;
      r.rating = one_of(text(v, "rating", true), kInstrumentRatings, "rating of " + name);
      r.comment = text(v, "comment", false);
      s.instruments[name] = r;
    }
  }
  static const char* kRatingText[] = {"",
                                      "very easy, highly desirable",
                                      "easy, desirable",
                                      "fair, mild difficulty",
                                      "minor but annoying difficulty",
                                      "moderately objectionable difficulty",
                                      "very objectionable but tolerable difficulty",
                                      "major difficulty",
                                      "major difficulty",
                                      "major difficulty",
                                      "impossible"};
  s.rating_text = kRatingText[static_cast<int>(s.rating)];  // a half step belongs to the rating below it
  return s;
}

}  // namespace vitreo::report
