#include "parallel/parallel_record.hpp"

namespace qdemsph {

void ParallelRecord::set_fluid(const FluidTraffic& t) {
  fluid_halo_bytes_per_step =
      t.evaluations > 0 ? static_cast<double>(t.halo_bytes) / static_cast<double>(t.evaluations)
                        : 0.0;
  fluid_migrated_bytes = t.migrated_bytes + t.band_bytes;
  fluid_rebuilds = t.rebuilds;
  fluid_recuts = t.recuts;
  fluid_skin = t.skin;
}

Json ParallelRecord::to_json() const {
  Json j = Json::object();
  j["ranks"] = ranks;
  j["curve"] = curve;
  j["rebalances"] = rebalances;
  j["rebuilds"] = rebuilds;
  j["contact_slack"] = contact_slack;
  j["imbalance"] = imbalance;
  j["imbalance_initial"] = imbalance_initial;
  j["imbalance_modelled"] = imbalance_modelled;
  j["migrated_bytes"] = migrated_bytes;
  j["halo_bytes_per_step"] = halo_bytes_per_step;
  j["fluid_halo_bytes_per_step"] = fluid_halo_bytes_per_step;
  j["fluid_migrated_bytes"] = fluid_migrated_bytes;
  j["fluid_rebuilds"] = fluid_rebuilds;
  j["fluid_recuts"] = fluid_recuts;
  j["fluid_skin"] = fluid_skin;
  j["setup_s"] = setup_s;
  Json ov = Json::array(), ot = Json::array();
  for (auto n : owned_vertices) ov.push_back(n);
  for (auto n : owned_tets) ot.push_back(n);
  j["owned_vertices"] = ov;
  j["owned_tets"] = ot;
  Json pmax = Json::object(), pmean = Json::object();
  for (const char* p : kParallelPhases) {
    const auto a = phases_max.find(p), b = phases_mean.find(p);
    pmax[p] = a == phases_max.end() ? 0.0 : a->second;
    pmean[p] = b == phases_mean.end() ? 0.0 : b->second;
  }
  j["phases_max"] = pmax;
  j["phases_mean"] = pmean;
  Json log = Json::array();
  for (const RebalanceEntry& e : rebalance_log) {
    Json r = Json::object();
    r["step"] = e.step;
    r["imbalance_before"] = e.imbalance_before;
    r["imbalance_after"] = e.imbalance_after;
    r["bytes"] = e.bytes;
    log.push_back(r);
  }
  j["rebalance_log"] = log;
  Json rebuilt = Json::array();
  for (const RebuildEntry& e : rebuild_log) {
    Json r = Json::object(), parts = Json::object();
    r["step"] = e.step;
    r["rebalance"] = e.rebalance;
    r["slack"] = e.slack;
    r["seconds"] = e.seconds;
    r["owners_changed"] = e.owners_changed;
    for (const auto& [k, v] : e.parts) parts[k] = v;
    r["parts"] = parts;
    rebuilt.push_back(r);
  }
  j["rebuild_log"] = rebuilt;
  Json by_rank = Json::array();
  for (const auto& m : phases_by_rank) {
    Json r = Json::object();
    for (const auto& [k, v] : m) r[k] = v;
    by_rank.push_back(r);
  }
  j["phases_by_rank"] = by_rank;
  return j;
}

ParallelRecord serial_parallel_record(const Model& model, const std::string& curve,
                                      const std::map<std::string, double>& phases) {
  ParallelRecord r;
  r.curve = curve;
  r.owned_vertices = {model.n_free_vertices};
  r.owned_tets = {model.n_free_tets};
  for (const char* p : kParallelPhases) {
    const auto it = phases.find(p);
    r.phases_max[p] = r.phases_mean[p] = it == phases.end() ? 0.0 : it->second;
  }
  r.phases_by_rank = {r.phases_max};
  return r;
}

}  // namespace qdemsph
