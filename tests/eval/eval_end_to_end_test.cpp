// Runs keepless_eval --quick end to end and checks the shape and sanity of
// what it reports. The paper's numbers are deliberately not asserted.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <sys/wait.h>

namespace {

// ---- a small JSON reader, enough for the summary line ----
struct Json {
  enum Kind { kNull, kBool, kNumber, kString, kArray, kObject } kind = kNull;
  double number = 0;
  bool boolean = false;
  std::string str;
  std::vector<Json> items;
  std::map<std::string, Json> fields;
  bool has(const std::string& k) const { return kind == kObject && fields.count(k) > 0; }
  const Json& at(const std::string& k) const { return fields.at(k); }
};

class Parser {
 public:
  explicit Parser(const std::string& s) : s_(s) {}
  bool parse(Json* out) {
    if (!value(out)) return false;
    ws();
    return i_ == s_.size();
  }

 private:
  void ws() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool lit(const char* w) {
    const std::string t(w);
    if (s_.compare(i_, t.size(), t) != 0) return false;
    i_ += t.size();
    return true;
  }
  bool string(std::string* out) {
    if (s_[i_] != '"') return false;
    ++i_;
    while (i_ < s_.size() && s_[i_] != '"') {
      if (s_[i_] == '\\') ++i_;
      if (i_ < s_.size()) out->push_back(s_[i_++]);
    }
    if (i_ >= s_.size()) return false;
    ++i_;
    return true;
  }
  bool value(Json* v) {
    ws();
    if (i_ >= s_.size()) return false;
    const char c = s_[i_];
    if (c == '{') {
      v->kind = Json::kObject;
      ++i_;
      ws();
      if (s_[i_] == '}') { ++i_; return true; }
      for (;;) {
        ws();
        std::string key;
        if (!string(&key)) return false;
        ws();
        if (s_[i_++] != ':') return false;
        if (!value(&v->fields[key])) return false;
        ws();
        if (s_[i_] == ',') { ++i_; continue; }
        if (s_[i_] == '}') { ++i_; return true; }
        return false;
      }
    }
    if (c == '[') {
      v->kind = Json::kArray;
      ++i_;
      ws();
      if (s_[i_] == ']') { ++i_; return true; }
      for (;;) {
        v->items.emplace_back();
        if (!value(&v->items.back())) return false;
        ws();
        if (s_[i_] == ',') { ++i_; continue; }
        if (s_[i_] == ']') { ++i_; return true; }
        return false;
      }
    }
    if (c == '"') {
      v->kind = Json::kString;
      return string(&v->str);
    }
    if (lit("null")) { v->kind = Json::kNull; return true; }
    if (lit("true")) { v->kind = Json::kBool; v->boolean = true; return true; }
    if (lit("false")) { v->kind = Json::kBool; return true; }
    char* end = nullptr;
    v->kind = Json::kNumber;
    v->number = std::strtod(s_.c_str() + i_, &end);
    if (end == s_.c_str() + i_) return false;
    i_ = static_cast<std::size_t>(end - s_.c_str());
    return true;
  }
  const std::string& s_;
  std::size_t i_ = 0;
};

struct RunOutput {
  int status = -1;
  std::string stdout_text;
  std::string last_line;
};

// stderr_only: stdout_text holds what the tool wrote to stderr instead.
RunOutput run(const std::string& args, bool stderr_only = false) {
  RunOutput r;
  const std::string cmd =
      std::string(KEEPLESS_EVAL_BIN) + " " + args + (stderr_only ? " 2>&1 >/dev/null" : " 2>/dev/null");
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.stdout_text.append(buf, n);
  const int st = pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  std::istringstream in(r.stdout_text);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) r.last_line = line;
  return r;
}

// The binary is part of this build: its absence is a failure, never a skip.
// Only missing data skips, saying which file is absent.
void require_binary() { ASSERT_TRUE(std::filesystem::exists(KEEPLESS_EVAL_BIN)) << KEEPLESS_EVAL_BIN << " was not built"; }
std::string data(const std::string& rel) { return std::string(KEEPLESS_EVAL_DATA) + "/" + rel; }
#define SKIP_WITHOUT(path)                                    \
  if (!std::filesystem::exists(path)) {                       \
    GTEST_SKIP() << "no data: " << (path) << " is missing"; \
  }

double num(const Json& o, const std::string& k) {
  EXPECT_TRUE(o.has(k)) << k;
  if (!o.has(k)) return NAN;
  EXPECT_EQ(o.at(k).kind, Json::kNumber) << k;
  return o.at(k).number;
}

// The keys the contract names (issue 11), on every run.
const char* const kContractKeys[] = {"input", "kind", "seeds", "M", "mp_percent", "kf_percent", "ba_time_percent",
                                     "ate_original_m", "ate_ours_m", "ate_ours_sd_m", "ate_random_m",
                                     "ate_longest_track_m", "ate_anms_m", "better_seeds", "worse_seeds",
                                     "sqrt_obs_ratio"};

TEST(KeeplessEval, QuickRunReportsTheContractForEveryInput) {
  require_binary();
  SKIP_WITHOUT(data("SOURCES.md"));
  const std::string out = (std::filesystem::temp_directory_path() / "keepless_eval_test_quick").string();
  std::filesystem::remove_all(out);
  const RunOutput r = run("--quick --cpus 0,1 --data-root " + std::string(KEEPLESS_EVAL_DATA) + " --out " + out);
  ASSERT_EQ(r.status, 0);
  Json j;
  ASSERT_TRUE(Parser(r.last_line).parse(&j)) << r.last_line;
  ASSERT_TRUE(j.has("runs"));
  EXPECT_EQ(j.at("mode").str, "quick");
  std::map<std::string, int> kinds;
  for (const Json& in : j.at("runs").items) {
    for (const char* k : kContractKeys) ASSERT_TRUE(in.has(k)) << k;
    const std::string kind = in.at("kind").str;
    ++kinds[kind];
    SCOPED_TRACE(in.at("input").str);
    const double seeds = num(in, "seeds");
    EXPECT_EQ(seeds, 2.0);  // --quick's default
    // --kept-fraction is a keep budget: no M is searched or used.
    EXPECT_EQ(num(in, "M"), 0.0);
    EXPECT_NEAR(num(in, "target_fraction"), 0.3, 1e-9);
    ASSERT_TRUE(in.has("failed_seeds"));
    for (const char* m : {"original", "ours", "random", "longest_track", "anms"}) {
      ASSERT_TRUE(in.at("failed_seeds").has(m)) << m;
      EXPECT_LE(num(in.at("failed_seeds"), m), seeds);
    }
    ASSERT_TRUE(in.has("frames") && in.has("frames_tracked"));
    // Sparsification keeps fewer points; it never adds any.
    const double mp = num(in, "mp_percent");
    EXPECT_GT(mp, 0.0);
    EXPECT_LT(mp, 100.0);
    EXPECT_GT(num(in, "kf_percent"), 0.0);
    EXPECT_LE(num(in, "kf_percent"), 400.0);  // fewer redundant points can mean fewer culled keyframes
    EXPECT_GT(num(in, "ba_time_percent"), 0.0);
    for (const char* k : {"ate_original_m", "ate_ours_m", "ate_ours_sd_m", "ate_random_m", "ate_longest_track_m"}) {
      const double v = num(in, k);
      EXPECT_TRUE(std::isfinite(v) && v >= 0) << k << " = " << v;
    }
    EXPECT_LE(num(in, "better_seeds") + num(in, "worse_seeds"), seeds);
    EXPECT_GT(num(in, "sqrt_obs_ratio"), 1.0);  // fewer points, fewer observations
    if (kind == "bal") {
      EXPECT_EQ(num(in, "ate_original_m"), 0.0);  // the full solution is the reference
      EXPECT_EQ(in.at("ate_anms_m").kind, Json::kNull);  // no keypoint responses in BAL
    } else {
      const double anms = num(in, "ate_anms_m");
      EXPECT_TRUE(std::isfinite(anms) && anms >= 0);
      // Equal count per window; the maps then evolve apart, but stay comparable.
      EXPECT_NEAR(num(in, "mp_percent_random"), mp, 25.0);
      EXPECT_NEAR(num(in, "mp_percent_longest_track"), mp, 25.0);
    }
    // Monocular images: Sim(3); the stereo back end: SE(3).
    if (kind == "images") {
      EXPECT_EQ(in.at("alignment").str, "sim3");
    }
    if (kind == "trajectory") {
      EXPECT_EQ(in.at("alignment").str, "se3");
      EXPECT_LT(num(in, "ate_original_m"), 0.5);  // a stereo back end on a desk-sized scene
    }
  }
  EXPECT_EQ(kinds["trajectory"], 1);
  EXPECT_EQ(kinds["images"], 1);
  EXPECT_EQ(kinds["bal"], 1);
  ASSERT_TRUE(j.has("ablation"));
  EXPECT_EQ(j.at("ablation").items.size(), 4u);  // all, c_c, c_c+c_s, c_c+c_b on TUM
  // Files: tables, CSV of every run, plots.
  for (const char* f : {"tables.md", "runs.csv", "ate_vs_kept.svg", "keypoints_ours_vs_anms.svg"})
    EXPECT_TRUE(std::filesystem::exists(out + "/" + f)) << f;
  std::ifstream csv(out + "/runs.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("input,name,group,kind,alignment,variant,seed,", 0), 0u);
  std::map<std::string, int> variants;
  while (std::getline(csv, line)) {
    std::stringstream ss(line);
    std::string field;
    for (int i = 0; i < 6 && std::getline(ss, field, ','); ++i) {}
    ++variants[field];
  }
  for (const char* v : {"original", "ours", "anms", "random", "longest_track"}) EXPECT_GE(variants[v], 2) << v;
  std::ifstream tables(out + "/tables.md");
  const std::string t((std::istreambuf_iterator<char>(tables)), std::istreambuf_iterator<char>());
  for (const char* h : {"Accuracy at equal kept fraction", "Baselines keeping the same count", "Per trajectory group",
                        "Cost ablation", "Which claims held"})
    EXPECT_NE(t.find(h), std::string::npos) << h;
  // The settings say where it ran: the CPUs granted, or why pinning was refused.
  EXPECT_TRUE(t.find("; cpus 0,1") != std::string::npos || t.find("(pinning to 0,1 refused: ") != std::string::npos);
  // --report regenerates the same contract from runs.csv, without running.
  const RunOutput again = run("--report " + out);
  ASSERT_EQ(again.status, 0);
  Json k;
  ASSERT_TRUE(Parser(again.last_line).parse(&k)) << again.last_line;
  ASSERT_EQ(k.at("runs").items.size(), j.at("runs").items.size());
  for (std::size_t i = 0; i < k.at("runs").items.size(); ++i)
    for (const char* key : {"seeds", "M", "mp_percent", "kf_percent", "ate_original_m", "ate_ours_m", "ate_random_m",
                            "better_seeds", "worse_seeds", "sqrt_obs_ratio"})
      EXPECT_EQ(num(k.at("runs").items[i], key), num(j.at("runs").items[i], key)) << key;
  EXPECT_EQ(k.at("ablation").items.size(), 4u);
  std::filesystem::remove_all(out);
}

TEST(KeeplessEval, NoiseFreeInputGivesNearZeroErrorAndIsDeterministic) {
  require_binary();
  const std::string tum = data("evo/freiburg1_xyz-groundtruth.txt");
  SKIP_WITHOUT(tum);
  const std::string args = "--quick --noise-free --no-ablation --seeds 1 --M 100 --max-keyframes 20 --seed 7 --trajectory " + tum + " --format tum";
  const RunOutput a = run(args), b = run(args);
  ASSERT_EQ(a.status, 0);
  ASSERT_EQ(b.status, 0);
  Json ja, jb;
  ASSERT_TRUE(Parser(a.last_line).parse(&ja));
  ASSERT_TRUE(Parser(b.last_line).parse(&jb));
  ASSERT_EQ(ja.at("runs").items.size(), 1u);
  const Json& in = ja.at("runs").items[0];
  // Exact measurements and odometry: the back end has nothing to correct.
  EXPECT_LT(num(in, "ate_original_m"), 1e-6);
  EXPECT_LT(num(in, "ate_r_original_deg"), 1e-4);
  EXPECT_LT(num(in, "ate_ours_m"), 1e-6);
  EXPECT_LT(num(in, "mp_percent"), 100.0);
  EXPECT_EQ(num(in, "M"), 100.0);
  // Same seed, same result (timings aside).
  const Json& in2 = jb.at("runs").items[0];
  for (const char* k : {"mp_percent", "kf_percent", "ate_original_m", "ate_ours_m", "ate_anms_m", "ate_random_m",
                        "ate_longest_track_m", "ate_r_ours_deg", "sqrt_obs_ratio"})
    EXPECT_EQ(num(in, k), num(in2, k)) << k;
}

// An input's numbers do not depend on which other inputs run, or in which
// order: each is seeded from its name.
TEST(KeeplessEval, AnInputGivesTheSameNumbersAloneOrInAnyOrder) {
  require_binary();
  const std::string tum = data("evo/freiburg1_xyz-groundtruth.txt");
  const std::string mh = data("orbslam3_euroc_left_cam_gt/MH01_GT.txt");
  SKIP_WITHOUT(tum);
  SKIP_WITHOUT(mh);
  const std::string common = " --quick --no-ablation --no-baselines --seeds 1 --M 100 --max-keyframes 12 ";
  const std::string A = "--trajectory " + tum + " --format tum", B = "--trajectory " + mh + " --format euroc";
  std::map<std::string, std::vector<double>> seen;  // name -> ATE (ours, original) per invocation
  for (const std::string& inputs : {A + " " + B, B + " " + A, A}) {
    const RunOutput r = run(common + inputs);
    ASSERT_EQ(r.status, 0) << inputs;
    Json j;
    ASSERT_TRUE(Parser(r.last_line).parse(&j));
    for (const Json& in : j.at("runs").items) {
      seen[in.at("name").str].push_back(num(in, "ate_ours_m"));
      seen[in.at("name").str].push_back(num(in, "ate_original_m"));
    }
  }
  ASSERT_EQ(seen["fr1_xyz"].size(), 6u);
  ASSERT_EQ(seen["MH01"].size(), 4u);
  for (std::size_t i = 2; i < 6; ++i) EXPECT_EQ(seen["fr1_xyz"][i], seen["fr1_xyz"][i % 2]) << i;
  EXPECT_EQ(seen["MH01"][2], seen["MH01"][0]);
  EXPECT_EQ(seen["MH01"][3], seen["MH01"][1]);
}

// A non-default policy and cost model run end to end with the baselines and
// give the same contract (keys, not numbers).
TEST(KeeplessEval, ANonDefaultPolicyGivesTheContract) {
  require_binary();
  const std::string tum = data("evo/freiburg1_xyz-groundtruth.txt");
  SKIP_WITHOUT(tum);
  const RunOutput r = run("--quick --no-ablation --seeds 1 --M 100 --max-keyframes 12 --scope newest --floor 30 "
                          "--cost information --trajectory " + tum + " --format tum");
  ASSERT_EQ(r.status, 0);
  Json j;
  ASSERT_TRUE(Parser(r.last_line).parse(&j));
  ASSERT_EQ(j.at("runs").items.size(), 1u);
  const Json& in = j.at("runs").items[0];
  for (const char* k : {"mp_percent", "kf_percent", "ate_original_m", "ate_ours_m", "ate_anms_m", "ate_random_m",
                        "ate_longest_track_m", "sqrt_obs_ratio"})
    EXPECT_TRUE(std::isfinite(num(in, k))) << k;
}

// --theta reaches keepless: at theta = 1 no flow is above the threshold, so
// keepless keeps fewer of the map's points than at the default 0.5.
TEST(KeeplessEval, ThetaReachesKeepless) {
  require_binary();
  const std::string tum = data("evo/freiburg1_xyz-groundtruth.txt");
  SKIP_WITHOUT(tum);
  const auto kept = [&](const std::string& theta) {
    const RunOutput r = run("--quick --no-ablation --no-baselines --seeds 1 --M 100 --max-keyframes 12 " + theta +
                            " --trajectory " + tum + " --format tum");
    EXPECT_EQ(r.status, 0);
    Json j;
    EXPECT_TRUE(Parser(r.last_line).parse(&j));
    return num(j.at("runs").items.at(0), "mp_percent");
  };
  const double by_default = kept(""), at_one = kept("--theta 1");
  EXPECT_LT(at_one, by_default);
  EXPECT_EQ(kept("--theta 0.5"), by_default);
}

// --track-share reaches keepless: other points kept, so another trajectory;
// a share of 0 is the default.
TEST(KeeplessEval, TrackShareReachesKeepless) {
  require_binary();
  const std::string tum = data("evo/freiburg1_xyz-groundtruth.txt");
  SKIP_WITHOUT(tum);
  const auto result = [&](const std::string& share) {
    const RunOutput r = run("--quick --no-ablation --no-baselines --seeds 1 --kept-fraction 0.3 --max-keyframes 12 " +
                            share + " --trajectory " + tum + " --format tum");
    EXPECT_EQ(r.status, 0);
    Json j;
    EXPECT_TRUE(Parser(r.last_line).parse(&j));
    return num(j.at("runs").items.at(0), "ate_ours_m");
  };
  const double by_order = result("");
  EXPECT_NE(result("--track-share 1"), by_order);
  EXPECT_EQ(result("--track-share 0"), by_order);
}

// Each bad flag is refused for itself: exit 2 with a message naming it,
// before any input is opened (the input named, /nonexistent, would also
// exit 2 but say "cannot open").
TEST(KeeplessEval, RejectsBadFlagsWithStatus2) {
  require_binary();
  const std::pair<const char*, const char*> cases[] = {
      {"--no-such-flag", "--no-such-flag"},
      {"--scope oldest", "--scope"},
      {"--cost cheap", "--cost"},
      {"--floor -1", "--floor"},
      {"--theta 1.5", "--theta"},
      {"--track-share 1.5 --kept-fraction 0.3", "--track-share"},
      {"--track-share 0.5 --M 100", "--track-share needs --kept-fraction"},
      {"--use offline --M 100", "--use offline takes a share of a count: give --kept-fraction"},
      {"--tracked-first --M 100", "--tracked-first needs --kept-fraction"},
      {"--decide oldest", "--decide"},
      {"--keyframe-culling sometimes", "--keyframe-culling"},
      {"--M abc", "--M"},
      {"--kept-fraction 1.5", "--kept-fraction"},
      {"--M 100 --kept-fraction 0.3", "exclude each other"},
      {"--seeds 0", "--seeds"},
      {"--error-floor tum", "--error-floor"},
      {"--bal /tmp/a,b.txt", "comma"},  // runs.csv could not hold it (it shifted every column)
  };
  for (const auto& [flags, says] : cases) {
    const RunOutput r = run(std::string(flags) + " --bal /nonexistent", /*stderr_only=*/true);
    EXPECT_EQ(r.status, 2) << flags;
    EXPECT_NE(r.stdout_text.find(says), std::string::npos) << flags << ": " << r.stdout_text;
    EXPECT_EQ(r.stdout_text.find("cannot open"), std::string::npos) << flags << ": " << r.stdout_text;
  }
  const RunOutput missing = run("--trajectory /nonexistent/file.txt --format tum", true);
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.stdout_text.find("/nonexistent/file.txt"), std::string::npos) << missing.stdout_text;
  const RunOutput none = run("", true);
  EXPECT_EQ(none.status, 2);
  EXPECT_FALSE(none.stdout_text.empty());  // says what input it needs
}

}  // namespace
