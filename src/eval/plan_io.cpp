// The plan file: Plan <-> JSON
#include "actionshift/eval/plan_io.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/store.hpp"
#include "io.hpp"

#include <nlohmann/json.hpp>

#include <set>

namespace actionshift::eval {

namespace {

using nlohmann::json;

void check_json_keys(const json& j, const std::set<std::string>& keys, const std::string& src, const std::string& field) {
  if (!j.is_object()) throw InputError(src, field, "expected an object");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!keys.count(it.key())) throw InputError(src, field.empty() ? it.key() : field + "." + it.key(), "unknown field");
  for (const auto& k : keys)
    if (!j.contains(k)) throw InputError(src, field.empty() ? k : field + "." + k, "missing field");
}

}  // namespace

nlohmann::json plan_to_json(const Plan& plan) {
  json j = json::object();
  j["schema_version"] = "1.0";
  j["experiment"] = plan.experiment;
  j["source"] = plan.source;
  j["source_sha256"] = plan.source_sha256;
  j["job_count"] = plan.jobs.size();
  j["jobs"] = json::array();
  for (const auto& pj : plan.jobs)
    j["jobs"].push_back({{"index", pj.index}, {"job_id", pj.job_id}, {"spec", job_to_json(pj.spec)}});
  return j;
}

Plan plan_from_json(const nlohmann::json& j, const std::string& source) {
  check_json_keys(j, {"schema_version", "experiment", "source", "source_sha256", "job_count", "jobs"}, source, "");
  if (j.at("schema_version") != "1.0") throw InputError(source, "schema_version", "unsupported plan schema version");
  Plan plan;
  if (!j.at("experiment").is_string() || !j.at("source").is_string() || !j.at("source_sha256").is_string())
    throw InputError(source, "experiment", "experiment, source and source_sha256 must be strings");
  plan.experiment = j.at("experiment").get<std::string>();
  plan.source = j.at("source").get<std::string>();
  plan.source_sha256 = j.at("source_sha256").get<std::string>();
  const json& jobs = j.at("jobs");
  if (!jobs.is_array()) throw InputError(source, "jobs", "expected a list");
  if (jobs.size() > kMaxPlanJobs)
    throw InputError(source, "jobs", std::to_string(jobs.size()) + " jobs, at most " + std::to_string(kMaxPlanJobs) + " in one plan");
  if (!j.at("job_count").is_number_integer() || j.at("job_count").get<std::int64_t>() != static_cast<std::int64_t>(jobs.size()))
    throw InputError(source, "job_count", "does not match the number of jobs (" + std::to_string(jobs.size()) + ")");
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const std::string f = "jobs[" + std::to_string(i) + "]";
    check_json_keys(jobs[i], {"index", "job_id", "spec"}, source, f);
    PlannedJob pj;
    const json& index = jobs[i].at("index");
    if (!index.is_number_integer() || index.get<std::int64_t>() != static_cast<std::int64_t>(i))
      throw InputError(source, f + ".index", "expected " + std::to_string(i));
    pj.index = static_cast<std::int64_t>(i);
    pj.spec = job_from_json(jobs[i].at("spec"), source + ": " + f + ".spec");
    pj.job_id = job_id(pj.spec);
    if (jobs[i].at("job_id") != pj.job_id)
      throw InputError(source, f + ".job_id", "does not match the hash of its spec (expected " + pj.job_id + ")");
    plan.jobs.push_back(std::move(pj));
  }
  return plan;
}

Plan load_plan(const std::string& path) {
  const std::string text = detail::read_file(path, "a plan file", kMaxInputFileBytes);
  return plan_from_json(parse_json_input(text, path), path);
}

void write_plan(const std::string& path, const Plan& plan) { write_json_atomic(path, plan_to_json(plan)); }

}  // namespace actionshift::eval
