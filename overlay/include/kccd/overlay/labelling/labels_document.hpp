// Labels documents as JSON, what a labelling page edits, and as the labels file's YAML text
// (docs/formats.md section 5): the same fields both ways, numbers that round-trip exactly.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "kccd/calib/labels.hpp"

namespace kccd::overlay {

/// The labels file's text for a labels document given as JSON (`{"labels": [{name, pixel, world}
/// or {name, pixel, body, point, state}, ...]}`): one label per line, each value written as JSON
/// writes it (a JSON value is a YAML flow value), so calib::parseLabels reads back exactly the
/// numbers given and reports what is wrong at the line where the saved file will have it. Keys
/// other than `labels` are kept for parseLabels to refuse. Throws calib::LabelsError naming `source`
/// when the document is not a JSON object or its `labels` is not a list.
std::string labelsYaml(const nlohmann::json& document, const std::string& source);

/// Whether a document has an empty `labels` list (nothing labelled yet; no labels file says so).
bool emptyLabels(const nlohmann::json& document);

/// The labels as a JSON document with the file's fields (`where` is not a field: left out).
nlohmann::json labelsJson(const calib::Labels& labels);

/// The labels of a document: labelsYaml, then calib::parseLabels with `source` naming it. Throws
/// calib::LabelsError (also for an empty list: a labels file needs at least one label).
calib::Labels parseLabelsDocument(const nlohmann::json& document, const std::string& source);

}  // namespace kccd::overlay
