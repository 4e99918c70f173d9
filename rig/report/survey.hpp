#pragma once
// The thesis' post-session evaluation (vitrectomy-simulator-thesis.txt, Appendix C: a modified
// Cooper-Harper survey after Wierwille and Casali, 1983), stored beside the session as
// DIR/survey.json (the report page's form writes it) and shown in the report.
//
// The form is a decision tree: can the procedure be accomplished most of the time (no: rating 10,
// impossible)? Are errors small and inconsequential (no: the error page, ratings 7–9)? Is the mental
// workload acceptable (no: the workload page, 4–6; yes: the easy page, 1–3)? Each page asks for an
// overall level on a five-point scale, which gives the rating in half steps (the thesis' Table II
// has 5.5 and 8.5), and for a level per category (image quality, modelling detail, tracking,
// physical interface, instrumentation). The last page rates each instrument (excellent … poor)
// with a comment. The mapping of the five points onto the scale's three ratings per band is our
// reading of the scale (README).
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace vitreo::report {

struct InstrumentRating {
  std::string rating;   // excellent, very_good, good, fair, poor
  std::string comment;
};

struct Survey {
  std::string subject, date;
  bool accomplished = true;
  std::optional<bool> errors_small, workload_acceptable;  // asked only when the answer before allows
  std::string page;      // "errors", "workload", "easy" or "" (not accomplished)
  std::string level;     // the page's overall level
  std::map<std::string, std::string> categories;  // category → level
  std::map<std::string, InstrumentRating> instruments;
  std::string comments;
  double rating = 10;    // modified Cooper-Harper, 1 (very easy) … 10 (impossible)
  std::string rating_text;
};

inline constexpr const char* kSurveyFormat = "vitreo-survey-1";

// Reads and checks DIR/survey.json's text. Throws std::runtime_error naming the first field that is
// missing or not one of its allowed values.
Survey parse_survey(const std::string& json_text);

// The levels a page allows, best first.
const std::vector<std::string>& survey_levels(const std::string& page);

}  // namespace vitreo::report
