// "Every refusal names the field", made checkable. The rules (also in docs/reliability_fuzz.md):
//
// YAML loaders (requireNamesYamlField): the message
//  1. begins with the path of the refused file (the case file) followed by ": ", and
//  2. names the place in it: if the message contains an assignment "<field> = <value>", the field
//     of the first one (indices and dotted prefixes stripped: gears.teeth[0] -> teeth) is a key of
//     the schema; otherwise the message contains a key or block of the schema as a whole word, or
//     says "unknown key" (it then quotes the key as written), or gives the line of a syntax error.
//  The schema is the list in field_rule.cpp: the keys the loaders document (README, "Config
//  files").
//
// Node parameters (requireNamesParameter): the message names, as a whole word, a parameter the
// node reads (with or without the leading ~).
//
// Anything else (requireNamesOneOf): the message contains one of the given fields as a whole word.
#pragma once

#include <string>
#include <vector>

namespace drivetrain_stiffness::fuzz {

/// Throws FuzzFinding unless `message` follows the YAML rule for the file at `path`.
void requireNamesYamlField(const std::string& message, const std::string& path);
/// Throws FuzzFinding unless `message` names a key or block of the schema (as a whole word): the
/// rule for refusals of a loaded rig by the estimator, which knows no file.
void requireNamesSchemaKey(const std::string& message);
/// Throws FuzzFinding unless `message` names one of the node's parameters.
void requireNamesParameter(const std::string& message);
/// Throws FuzzFinding unless `message` names one of `fields`; `what` says where it came from.
void requireNamesOneOf(const std::string& message, const std::vector<std::string>& fields,
                       const std::string& what);

/// The node's parameter names (config/stiffness_estimator.yaml and the pipeline's options).
const std::vector<std::string>& nodeParameterNames();
/// True if `word` occurs in `text` delimited by characters that cannot be part of an identifier.
bool containsWord(const std::string& text, const std::string& word);

}  // namespace drivetrain_stiffness::fuzz
