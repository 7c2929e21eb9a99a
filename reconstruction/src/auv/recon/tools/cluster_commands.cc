// `auv recon status <survey>` and `auv recon cancel <survey>`: the Slurm jobs of the survey's
// last `auv recon run --executor slurm` (cluster/README.md).
#include <iomanip>
#include <iostream>

#include "auv/recon/cluster/slurm_run.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

/// Parses `<survey>` (and --help); false when help was printed.
bool parseSurvey(const std::string& command, const std::vector<std::string>& args,
                 std::string& survey) {
  OptionSet set(command);
  set.positional("survey", &survey, "survey folder of an `auv recon run --executor slurm`");
  return set.parse(args);
}

int statusMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("status", [&] {
    std::string survey;
    if (!parseSurvey("status", args, survey)) return tools::kExitOk;
    const auto jobs = cluster::surveyJobs(Survey(survey));
    std::cout << std::left << std::setw(17) << "stage" << std::setw(10) << "job" << std::setw(14)
              << "state" << std::setw(12) << "elapsed" << std::setw(10) << "node"
              << "reason / log\n";
    size_t done = 0, failed = 0;
    for (const auto& j : jobs) {
      done += j.info.state == "COMPLETED";
      const bool bad = cluster::slurm::finished(j.info.state) && j.info.state != "COMPLETED" &&
                       j.info.state != "UNKNOWN";
      failed += bad;
      const std::string name = j.job.stage + (j.job.part.empty() ? "" : "." + j.job.part);
      std::cout << std::setw(17) << name << std::setw(10) << j.job.id << std::setw(14)
                << j.info.state << std::setw(12) << j.info.elapsed << std::setw(10) << j.info.nodes
                << (bad ? (Survey(survey).root() / j.job.log).string() : j.info.reason) << "\n";
    }
    std::cout << "status: " << done << " of " << jobs.size() << " jobs completed"
              << (failed ? ", " + std::to_string(failed) +
                               " failed (its log is named; `auv recon run --executor slurm` again "
                               "redoes what is missing)"
                         : "")
              << std::endl;
    return failed ? tools::kExitFailed : tools::kExitOk;
  });
}

int cancelMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("cancel", [&] {
    std::string survey;
    if (!parseSurvey("cancel", args, survey)) return tools::kExitOk;
    const auto ids = cluster::cancelSurveyJobs(Survey(survey));
    std::cout << "cancel: " << ids.size() << " job(s) cancelled";
    for (const auto& id : ids) std::cout << " " << id;
    std::cout << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("status", 101, "<survey>   the Slurm jobs of `run --executor slurm`", statusMain);
AUV_RECON_COMMAND("cancel", 102, "<survey>   cancel those jobs", cancelMain);

}  // namespace auv::recon
