#pragma once
/// \file The plan file (docs/formats.md "Plan file"): a Plan as JSON, read back with every job id
/// checked against its spec.

#include "actionshift/eval/plan_expand.hpp"

#include <nlohmann/json_fwd.hpp>

#include <string>

namespace actionshift::eval {

/// Plan file object: {"schema_version","experiment","source","source_sha256","job_count","jobs":[{"index","job_id","spec"}]}.
nlohmann::json plan_to_json(const Plan& plan);

/// Inverse of plan_to_json. Each stored job_id is checked against its recomputed spec hash and each
/// index against its position. Throws actionshift::InputError(source, field, reason).
Plan plan_from_json(const nlohmann::json& j, const std::string& source);

/// Read a plan file (as plan_from_json).
Plan load_plan(const std::string& path);

/// Write a plan file atomically (indented JSON).
void write_plan(const std::string& path, const Plan& plan);

}  // namespace actionshift::eval
