#include "design/runner.h"

#include <atomic>
#include <fstream>
#include <mutex>
#include <thread>

namespace tangent::design {

namespace {

// The cases recorded in a journal; a line that does not parse (the run was killed while writing
// it) is skipped.
void ReadJournal(const std::string& path, std::map<int, nlohmann::json>* done) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("case") || !j["case"].is_number_integer())
      continue;
    (*done)[j["case"].get<int>()] = j;
  }
}

}  // namespace

std::map<int, nlohmann::json> RunCases(const Study& study, const std::vector<int>& share,
                                       const RunnerOptions& options) {
  std::map<int, nlohmann::json> resumed;
  for (const std::string& path : options.resume_from) ReadJournal(path, &resumed);
  std::map<int, nlohmann::json> results;
  std::vector<int> todo;
  for (int i : share) {
    const auto it = resumed.find(i);
    if (it != resumed.end()) {
      results[i] = it->second;
    } else {
      todo.push_back(i);
    }
  }
  std::ofstream journal;
  if (!options.journal.empty()) journal.open(options.journal, std::ios::app);
  std::mutex lock;
  std::atomic<size_t> next{0};
  int done = static_cast<int>(results.size());
  auto worker = [&] {
    for (size_t k = next++; k < todo.size(); k = next++) {
      nlohmann::json j;
      try {
        j = study.ToJson(study.Solve(todo[k]));
      } catch (const std::exception& e) {  // (e.g. a measure undefined at this start)
        CaseResult failed;
        failed.index = todo[k];
        failed.status = std::string("failed: ") + e.what();
        j = study.ToJson(failed);
      }
      const std::lock_guard<std::mutex> guard(lock);
      if (journal.is_open()) {
        journal << j.dump() << '\n';
        journal.flush();
      }
      ++done;
      if (options.progress) options.progress(done, static_cast<int>(share.size()), j);
      results[todo[k]] = std::move(j);
    }
  };
  const int threads = std::max(1, std::min<int>(options.threads, static_cast<int>(todo.size())));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  return results;
}

nlohmann::json ResultFile(const Study& study, const std::map<int, nlohmann::json>& cases) {
  nlohmann::json out = study.Header();
  nlohmann::json list = nlohmann::json::array();
  int best = -1;
  double best_value = 0.0;
  int optima = 0;
  for (const auto& [index, j] : cases) {
    list.push_back(j);
    if (j.value("status", "") != "optimum") continue;
    ++optima;
    const double f = j["objective"].get<double>();
    if (best < 0 || (study.run().maximize ? f > best_value : f < best_value)) {
      best = index;
      best_value = f;
    }
  }
  out["optima"] = optima;
  out["best_case"] = best >= 0 ? nlohmann::json(best) : nlohmann::json(nullptr);
  if (best >= 0) {
    out["best_objective"] = best_value;
    const std::vector<double> q = cases.at(best)["q"].get<std::vector<double>>();
    out["best_geometry"] = study.Geometry(
        Eigen::Map<const Eigen::VectorXd>(q.data(), static_cast<Eigen::Index>(q.size())));
  }
  out["results"] = list;
  return out;
}

nlohmann::json WithoutTimings(nlohmann::json result) {
  if (result.contains("results")) {
    for (nlohmann::json& c : result["results"]) c.erase("time_ms");
  }
  result.erase("time_ms");
  return result;
}

}  // namespace tangent::design
