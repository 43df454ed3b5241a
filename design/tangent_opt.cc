// tangent-opt RUN.json: an offline design study (docs/offline.md). Every start of the run file
// is solved to convergence on all cores (threads over one shared problem); under MPI
// (`mpirun -np N tangent-opt RUN.json`) each rank takes every N-th case and rank 0 gathers one
// result file. Finished cases are journalled as they complete; --resume skips them.

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>

#include "design/runner.h"
#include "design/study.h"

#ifdef TANGENT_WITH_MPI
#include <mpi.h>
#endif

namespace {

using tangent::design::RunError;

struct Ranks {
  int rank = 0, size = 1;
};

Ranks StartRanks(int* argc, char*** argv) {
  Ranks r;
#ifdef TANGENT_WITH_MPI
  // Only under an MPI launcher: a plain run starts no MPI runtime.
  if (std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMI_SIZE") || std::getenv("PMIX_RANK")) {
    MPI_Init(argc, argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &r.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &r.size);
  }
#else
  (void)argc;
  (void)argv;
#endif
  return r;
}

void StopRanks(const Ranks& r) {
#ifdef TANGENT_WITH_MPI
  int started = 0;
  MPI_Initialized(&started);
  if (started) MPI_Finalize();
#endif
  (void)r;
}

// Rank 0 receives every rank's cases (a JSON array each); the other ranks get nothing back.
std::map<int, nlohmann::json> Gather(const Ranks& r, const std::map<int, nlohmann::json>& mine) {
  if (r.size == 1) return mine;
#ifdef TANGENT_WITH_MPI
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [i, j] : mine) list.push_back(j);
  const std::string text = list.dump();
  int length = static_cast<int>(text.size());
  std::vector<int> lengths(static_cast<size_t>(r.size)), offsets(static_cast<size_t>(r.size));
  MPI_Gather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string all;
  if (r.rank == 0) {
    int total = 0;
    for (int k = 0; k < r.size; ++k) {
      offsets[static_cast<size_t>(k)] = total;
      total += lengths[static_cast<size_t>(k)];
    }
    all.resize(static_cast<size_t>(total));
  }
  MPI_Gatherv(text.data(), length, MPI_CHAR, all.data(), lengths.data(), offsets.data(), MPI_CHAR,
              0, MPI_COMM_WORLD);
  std::map<int, nlohmann::json> merged;
  if (r.rank == 0) {
    for (int k = 0; k < r.size; ++k) {
      const auto part =
          nlohmann::json::parse(all.substr(static_cast<size_t>(offsets[static_cast<size_t>(k)]),
                                           static_cast<size_t>(lengths[static_cast<size_t>(k)])));
      for (const nlohmann::json& j : part) merged[j["case"].get<int>()] = j;
    }
  }
  return merged;
#else
  return mine;
#endif
}

// The journals of an earlier run of the same output (any rank count).
std::vector<std::string> Journals(const std::string& output) {
  std::vector<std::string> found;
  const std::filesystem::path out(output);
  const std::filesystem::path dir = out.has_parent_path() ? out.parent_path() : ".";
  const std::string prefix = out.filename().string() + ".partial";
  if (!std::filesystem::is_directory(dir)) return found;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().filename().string().rfind(prefix, 0) == 0) found.push_back(e.path().string());
  }
  return found;
}

}  // namespace

int main(int argc, char** argv) {
  const Ranks ranks = StartRanks(&argc, &argv);
  CLI::App app{"tangent-opt: offline design studies (docs/offline.md)"};
  std::string run_path, output;
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool resume = false, quiet = false;
  app.add_option("run", run_path, "the run file (JSON)")->required();
  app.add_option("-o,--output", output, "the result file (default: RUN.result.json)");
  app.add_option("--threads", threads, "threads per process (default: all cores)")
      ->check(CLI::Range(1, 1024));
  app.add_flag("--resume", resume, "keep the cases an interrupted run of this output finished");
  app.add_flag("--quiet", quiet, "no progress bar or summary");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    StopRanks(ranks);
    return code;
  }
  if (output.empty()) {
    std::filesystem::path p(run_path);
    // x.run.json (the examples' naming) or x.json -> x.result.json, beside the run file.
    std::string stem = p.stem().string();
    if (stem.size() > 4 && stem.compare(stem.size() - 4, 4, ".run") == 0)
      stem.resize(stem.size() - 4);
    output = (p.parent_path() / (stem + ".result.json")).string();
  }
  int status = 0;
  try {
    const tangent::design::Study study(tangent::design::LoadRun(run_path));
    std::vector<int> share;
    for (int i = ranks.rank; i < study.num_cases(); i += ranks.size) share.push_back(i);
    tangent::design::RunnerOptions o;
    o.threads = threads;
    o.journal = output + ".partial" + (ranks.size > 1 ? ".rank" + std::to_string(ranks.rank) : "");
    if (resume) {
      o.resume_from = Journals(output);
    } else {
      std::filesystem::remove(o.journal);
    }
    const auto start = std::chrono::steady_clock::now();
    const bool bar = !quiet && ranks.rank == 0 && isatty(STDERR_FILENO);
    bool drawn = false;
    o.progress = [&](int done, int total, const nlohmann::json& j) {
      const double s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (!bar || (s < 1.0 && done < total)) return;
      const int width = 30, filled = total ? width * done / total : width;
      std::fprintf(stderr, "\r[%-*s] %d/%d cases  %.1f s  last: %s %.6g", width,
                   std::string(static_cast<size_t>(filled), '#').c_str(), done, total, s,
                   j["status"].get<std::string>().c_str(), j["objective"].get<double>());
      drawn = true;
    };
    const auto mine = tangent::design::RunCases(study, share, o);
    if (drawn) std::fprintf(stderr, "\n");
    const auto all = Gather(ranks, mine);
    if (ranks.rank == 0) {
      const nlohmann::json result = tangent::design::ResultFile(study, all);
      std::ofstream out(output);
      if (!out) throw RunError(output + ": cannot write the result file");
      out << result.dump(1) << '\n';
      out.close();
      for (const std::string& j : Journals(output)) std::filesystem::remove(j);
      if (!quiet) {
        std::printf("tangent-opt: %d cases, %d optima", study.num_cases(),
                    result["optima"].get<int>());
        if (!result["best_case"].is_null()) {
          std::printf(", best %s %.10g (case %d)", study.run().maximize ? "maximum" : "minimum",
                      result["best_objective"].get<double>(), result["best_case"].get<int>());
        }
        std::printf("; written to %s\n", output.c_str());
      }
    }
  } catch (const RunError& e) {
    if (ranks.rank == 0) std::fprintf(stderr, "tangent-opt: %s\n", e.what());
    status = 2;
  } catch (const std::exception& e) {
    if (ranks.rank == 0) std::fprintf(stderr, "tangent-opt: %s\n", e.what());
    status = 3;
  }
  StopRanks(ranks);
  return status;
}
