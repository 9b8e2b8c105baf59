// The sections of the configuration schema (see the header comment of config/config.h), read
// with the TableReader of config/config_toml.h.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <system_error>

#include "config/config_toml.h"
#include "config/resources.h"
#include "messages/batch.h"
#include "messages/channels.h"
#include "solver/fatigue/law_registry.h"

namespace peritwin::config::config_internal {

namespace {

/// A required number within `bound`.
std::optional<double> req(TableReader& r, std::string_view key, core::Bound bound) {
  const std::optional<double> v = r.number(key);
  if (v && !r.check(key, core::satisfies(*v, bound), core::bound_reason(*v, bound)))
    return std::nullopt;
  return v;
}

/// An optional number within `bound`.
double opt(TableReader& r, std::string_view key, double fallback, core::Bound bound) {
  const double v = r.number(key, fallback);
  r.check(key, core::satisfies(v, bound), core::bound_reason(v, bound));
  return v;
}

/// Calls f(table, path) for every element of the array of tables at `key`.
template <typename F>
void each_table(TableReader& r, std::string_view key, bool required, std::string_view expected,
                F&& f) {
  const toml::node* n = r.node(key, required);
  if (n == nullptr) return;
  Context& ctx = r.context();
  const std::string path = r.path_of(key);
  const toml::array* a = n->as_array();
  if (a == nullptr) {
    ctx.error(n->source(), path,
              "expected " + std::string(expected) + ", got " + std::string(type_name(n->type())));
    return;
  }
  if (required && a->empty()) ctx.error(n->source(), path, "at least one entry is required");
  for (std::size_t i = 0; i < a->size(); ++i) {
    const std::string element_path = path + "[" + std::to_string(i) + "]";
    if (const auto* t = (*a)[i].as_table()) {
      f(*t, element_path);
    } else {
      ctx.error((*a)[i].source(), element_path,
                "expected a table, got " + std::string(type_name((*a)[i].type())));
    }
  }
}

std::optional<mesh::Rectangle> read_rectangle(TableReader& r) {
  const auto x0 = r.number("x_min");
  const auto y0 = r.number("y_min");
  const auto x1 = r.number("x_max");
  const auto y1 = r.number("y_max");
  if (!x0 || !y0 || !x1 || !y1) return std::nullopt;
  bool ok = r.check("x_max", *x1 > *x0, "must be > x_min = " + core::format_number(*x0));
  ok = r.check("y_max", *y1 > *y0, "must be > y_min = " + core::format_number(*y0)) && ok;
  if (!ok) return std::nullopt;
  return mesh::Rectangle{*x0, *y0, *x1, *y1};
}

std::optional<mesh::Circle> read_circle(TableReader& r) {
  const auto centre = r.point("centre");
  const auto radius = req(r, "radius", core::Bound::positive);
  if (!centre || !radius) return std::nullopt;
  return mesh::Circle{*centre, *radius};
}

constexpr std::string_view kVertexForms =
    "a vertex [x, y], { at = [x, y], fillet = r } or { to = [x, y], arc_centre = [x, y], "
    "direction = \"ccw\" | \"cw\" }";

/// One polygon vertex: [x, y] | { at = [x, y], fillet = r } (a corner, rounded when r > 0) |
/// { to = [x, y], arc_centre = [x, y], direction = "ccw" | "cw" } (the edge arriving at it is an
/// arc).
std::optional<mesh::PolygonVertex> read_vertex(Context& ctx, const toml::node& n,
                                               const std::string& path) {
  if (n.is_array()) {
    const auto p = point_of(ctx, n, path);
    if (!p) return std::nullopt;
    return mesh::PolygonVertex{*p, mesh::PolygonVertex::Edge::straight, {}, 0.0};
  }
  const toml::table* t = n.as_table();
  if (t == nullptr) {
    ctx.error(
        n.source(), path,
        "expected " + std::string(kVertexForms) + ", got " + std::string(type_name(n.type())));
    return std::nullopt;
  }
  TableReader r(ctx, *t, path);
  std::optional<mesh::PolygonVertex> vertex;
  if (r.has("to") || r.has("arc_centre") || r.has("direction")) {
    const auto to = r.point("to");
    const auto centre = r.point("arc_centre");
    const auto direction = r.choice<mesh::PolygonVertex::Edge>(
        "direction",
        {{"ccw", mesh::PolygonVertex::Edge::arc_ccw}, {"cw", mesh::PolygonVertex::Edge::arc_cw}},
        std::nullopt);
    for (const char* key : {"at", "fillet"}) {
      r.node(key, false);
      r.check(key, !r.has(key),
              "not in an arc vertex (an arc's end takes no fillet; its point is \"to\")");
    }
    if (to && centre && direction) vertex = mesh::PolygonVertex{*to, *direction, *centre, 0.0};
  } else {
    const auto at = r.point("at");
    const double fillet = opt(r, "fillet", 0.0, core::Bound::non_negative);
    if (at) vertex = mesh::PolygonVertex{*at, mesh::PolygonVertex::Edge::straight, {}, fillet};
  }
  r.finish();
  return vertex;
}

/// polygon = [vertex, ...] of the table read by r, validated by Polygon::make (errors at
/// "<path>.polygon[k]", k the vertex to blame).
std::optional<mesh::Polygon> read_polygon(Context& ctx, TableReader& r) {
  const toml::array* a = r.array("polygon", true);
  if (a == nullptr) return std::nullopt;
  const std::string path = r.path_of("polygon");
  std::vector<mesh::PolygonVertex> vertices;
  bool ok = true;
  for (std::size_t i = 0; i < a->size(); ++i) {
    if (const auto v = read_vertex(ctx, (*a)[i], path + "[" + std::to_string(i) + "]")) {
      vertices.push_back(*v);
    } else {
      ok = false;
    }
  }
  if (!ok) return std::nullopt;
  auto polygon = mesh::Polygon::make(std::move(vertices));
  if (!polygon) {
    const core::Error& e = polygon.error();
    const toml::node* where = a;
    if (e.field.size() > 2 && e.field.front() == '[') {
      const std::size_t k = std::strtoull(e.field.c_str() + 1, nullptr, 10);
      if (k < a->size()) where = &(*a)[k];
    }
    ctx.error(where->source(), path + e.field, e.reason);
    return std::nullopt;
  }
  return std::move(polygon).value();
}

/// {x_min, y_min, x_max, y_max}, {centre = [x, y], radius} or {polygon = [vertex, ...]}.
std::optional<mesh::Region> read_region(Context& ctx, const toml::table& t,
                                        const std::string& path) {
  TableReader r(ctx, t, path);
  std::optional<mesh::Region> region;
  if (r.has("polygon")) {
    if (auto p = read_polygon(ctx, r)) region = mesh::Region::of(std::move(*p));
  } else if (r.has("centre") || r.has("radius")) {
    if (const auto c = read_circle(r)) region = mesh::Region::of(*c);
  } else if (r.has("x_min") || r.has("y_min") || r.has("x_max") || r.has("y_max")) {
    if (const auto rect = read_rectangle(r)) region = mesh::Region::of(*rect);
  } else {
    for (const auto* key : {"x_min", "y_min", "x_max", "y_max", "centre", "radius", "polygon"}) {
      r.node(key, false);
    }
    r.error(
        "expected a rectangle {x_min, y_min, x_max, y_max}, a circle {centre, radius} or a "
        "polygon {polygon = [vertex, ...]}");
  }
  r.finish();
  return region;
}

bool inside_outline(const std::vector<mesh::Region>& outline, mesh::Point p) {
  return std::any_of(outline.begin(), outline.end(), [p](const auto& r) { return r.contains(p); });
}

/// Reads [detail.geometry]; returns true when the outline is complete and valid.
bool read_geometry(Context& ctx, const toml::table& t, const std::string& path,
                   mesh::DetailGeometry& g) {
  const std::size_t errors_before = ctx.errors.size();
  TableReader r(ctx, t, path);
  if (const auto h = req(r, "thickness", core::Bound::positive)) g.thickness = *h;
  g.rigid_model = r.choice<mesh::RigidModel>("rigid_model",
                                             {{"constraint", mesh::RigidModel::constraint},
                                              {"stiff_material", mesh::RigidModel::stiff_material}},
                                             g.rigid_model)
                      .value_or(g.rigid_model);
  g.rigid_factor = r.number("rigid_factor", 200.0);
  r.check("rigid_factor", g.rigid_factor >= 1, "must be >= 1 (E_rigid / E)");
  g.rigid_penalty = r.number("rigid_penalty", g.rigid_penalty);
  r.check("rigid_penalty", g.rigid_penalty >= 1,
          "must be >= 1 (a rigid region's tie stiffness / its bond's)");
  bool outline_ok = r.has("outline");
  each_table(r, "outline", true, "an array of rectangles, polygons or circles",
             [&](const auto& e, const auto& p) {
               if (auto region = read_region(ctx, e, p)) {
                 g.outline.push_back(std::move(*region));
               } else {
                 outline_ok = false;
               }
             });
  outline_ok = outline_ok && !g.outline.empty();
  each_table(
      r, "holes", false, "an array of circles or polygons", [&](const auto& e, const auto& p) {
        const std::size_t before = ctx.errors.size();
        auto hole = read_region(ctx, e, p);
        if (!hole) return;
        if (outline_ok && ctx.errors.size() == before) {
          // DetailGeometry::validate's test, for this hole alone
          mesh::DetailGeometry probe;
          probe.outline = g.outline;
          probe.holes = {*hole};
          std::string why = core::message_of(probe.validate());
          if (const auto colon = why.find(": "); why.starts_with("holes[") && colon != why.npos) {
            why = why.substr(colon + 2);
          }
          if (!why.empty()) ctx.error(e.source(), p, why);
        }
        g.holes.push_back(std::move(*hole));
      });
  each_table(r, "notches", false, "an array of notches", [&](const auto& e, const auto& p) {
    TableReader er(ctx, e, p);
    mesh::Notch notch;
    notch.name = er.string("name", "notch " + std::to_string(g.notches.size()));
    bool ok = true;
    if (er.has("path")) {
      for (const char* key : {"from", "to"}) {
        er.node(key, false);
        ok = er.check(key, !er.has(key), "give either \"path\" or \"from\" and \"to\"") && ok;
      }
      if (const toml::array* a = er.array("path", true)) {
        const std::string points = er.path_of("path");
        for (std::size_t i = 0; i < a->size(); ++i) {
          const std::string at = points + "[" + std::to_string(i) + "]";
          const auto q = point_of(ctx, (*a)[i], at);
          if (!q) {
            ok = false;
          } else if (!notch.path.empty() && q->x == notch.path.back().x &&
                     q->y == notch.path.back().y) {
            ctx.error((*a)[i].source(), at, "repeats the previous point");
            ok = false;
          } else {
            notch.path.push_back(*q);
          }
        }
        ok = er.check("path", a->size() >= 2,
                      "needs at least 2 points, from the mouth to the tip (got " +
                          std::to_string(a->size()) + ")") &&
             ok;
      } else {
        ok = false;
      }
    } else {
      const auto a = er.point("from");
      const auto b = er.point("to");
      ok = a && b && er.check("to", a->x != b->x || a->y != b->y, "must differ from \"from\"");
      if (ok) notch.path = {*a, *b};
    }
    if (ok) g.notches.push_back(std::move(notch));
    er.finish();
  });
  for (const auto* key : {"rigid_regions", "no_fail_zones"}) {
    auto& regions = std::string_view(key) == "rigid_regions" ? g.rigid_regions : g.no_fail_zones;
    each_table(r, key, false, "an array of regions", [&](const auto& e, const auto& p) {
      if (const auto region = read_region(ctx, e, p)) regions.push_back(*region);
    });
  }
  r.finish();
  if (ctx.errors.size() == errors_before) {
    if (const core::Status valid = g.validate(); !valid) r.error(valid.error().reason);
  }
  return outline_ok;
}

void read_grid(Context& ctx, const toml::table& t, const std::string& path,
               const mesh::Rectangle* box, DetailConfig& d) {
  TableReader r(ctx, t, path);
  if (const auto dx = req(r, "dx", core::Bound::positive)) {
    d.dx = *dx;
    if (box != nullptr) {
      const double side = std::min(box->x_max - box->x_min, box->y_max - box->y_min);
      r.check("dx", *dx <= side,
              "must not exceed the body's smaller side " + core::format_number(side) + " m (got " +
                  core::format_number(*dx) + ")");
    }
  }
  d.horizon_ratio = r.number("horizon_ratio", 3.015);
  if (r.check("horizon_ratio", d.horizon_ratio >= kMinHorizonRatio,
              "must be >= 1: the horizon δ = horizon_ratio·dx may not be smaller than dx (got " +
                  core::format_number(d.horizon_ratio) + ")")) {
    r.check("horizon_ratio", d.horizon_ratio <= kMaxHorizonRatio,
            "must be <= " + core::format_number(kMaxHorizonRatio) +
                ": peridynamic fatigue calibrations use 3 to 4 (000: δ = 3.015Δx), and a node's "
                "family grows as π·horizon_ratio² bonds (314 at 10), the factor with it (got " +
                core::format_number(d.horizon_ratio) + ")");
  }
  r.finish();
}

void read_model(Context& ctx, const toml::table& t, const std::string& path,
                model::ModelOptions& m) {
  TableReader r(ctx, t, path);
  m.kind = r.choice<model::ModelKind>("kind",
                                      {{"bond_based", model::ModelKind::bond_based},
                                       {"state_based", model::ModelKind::state_based}},
                                      m.kind)
               .value_or(m.kind);
  m.kernel = r.choice<model::Kernel>("kernel",
                                     {{"constant", model::Kernel::constant},
                                      {"conical", model::Kernel::conical},
                                      {"gaussian", model::Kernel::gaussian}},
                                     m.kernel)
                 .value_or(m.kernel);
  m.plane = r.choice<model::PlaneCondition>("plane",
                                            {{"plane_stress", model::PlaneCondition::plane_stress},
                                             {"plane_strain", model::PlaneCondition::plane_strain}},
                                            m.plane)
                .value_or(m.plane);
  m.surface_correction = r.boolean("surface_correction", m.surface_correction);
  r.check("kernel", m.kind == model::ModelKind::bond_based || m.kernel == model::Kernel::constant,
          "the state-based model (000 Eq. 4) takes the constant kernel only");
  r.finish();
}

void read_material(Context& ctx, const toml::table& t, const std::string& path,
                   model::Material& m) {
  TableReader r(ctx, t, path);
  if (const auto e = req(r, "E", core::Bound::positive)) m.youngs_modulus = *e;
  if (const auto nu = r.number("nu")) {
    m.poisson_ratio = *nu;
    r.check("nu", *nu > -1.0 && *nu < 0.5,
            "must lie in (-1, 0.5) (got " + core::format_number(*nu) + ")");
  }
  m.fracture_toughness = opt(r, "K_c", 0.0, core::Bound::non_negative);
  // Material scatter (004, model::node_youngs_moduli): σ_E < E/5 keeps every clamped draw > 0.
  m.youngs_modulus_std = opt(r, "E_std", 0.0, core::Bound::non_negative);
  if (m.youngs_modulus > 0 && m.youngs_modulus_std > 0) {
    r.check("E_std", m.youngs_modulus_std < m.youngs_modulus / 5.0,
            "must be < E/5 = " + core::format_number(m.youngs_modulus / 5.0) +
                " Pa (each node's E is clamped to E ± 4·E_std, which must stay > 0; got " +
                core::format_number(m.youngs_modulus_std) + ")");
  }
  const std::int64_t seed = r.integer("E_seed", 0);
  r.check("E_seed", seed >= 0, "must be >= 0");
  m.youngs_modulus_seed = static_cast<std::uint64_t>(std::max<std::int64_t>(seed, 0));
  r.finish();
}

/// [detail.fatigue] compression (issue 34, FatigueSettings::compression) and the closure rule's
/// closure_constraint, closure_smax_over_flow_stress (fatigue::NewmanClosure).
void read_compression(TableReader& r, fatigue::FatigueSettings& f) {
  const std::vector<std::pair<std::string_view, fatigue::CompressionRule>> rules = {
      {"full_range", fatigue::CompressionRule::full_range},
      {"contact", fatigue::CompressionRule::contact},
      {"closure", fatigue::CompressionRule::closure}};
  f.compression = r.choice<fatigue::CompressionRule>("compression", rules, f.compression)
                      .value_or(f.compression);
  const bool range_law =
      f.law == fatigue::FatigueLaw::strain_range || f.law == fatigue::FatigueLaw::energy;
  if (f.compression != fatigue::CompressionRule::full_range) {
    r.check("compression", range_law,
            "applies to the laws strain_range and energy (000 Eq. 15); the kinetic law takes R "
            "in its own dose (004 Eq. 15) and the bilinear law holds the load at its peak (003 "
            "Sec. 4)");
  }
  if (f.compression == fatigue::CompressionRule::contact) {
    r.check("compression", f.law == fatigue::FatigueLaw::strain_range,
            "\"contact\" needs law = \"strain_range\" (each bond's range from the contact "
            "solution at P_min)");
  }
  const bool closure = f.compression == fatigue::CompressionRule::closure;
  for (const auto* key : {"closure_constraint", "closure_smax_over_flow_stress"}) {
    if (r.has(key)) r.check(key, closure, "only with compression = \"closure\"");
  }
  f.closure.constraint = r.number("closure_constraint", f.closure.constraint);
  r.check("closure_constraint", f.closure.constraint >= 1.0 && f.closure.constraint <= 3.0,
          "must lie in [1, 3] (1 plane stress, 3 plane strain; got " +
              core::format_number(f.closure.constraint) + ")");
  f.closure.smax_over_flow_stress =
      r.number("closure_smax_over_flow_stress", f.closure.smax_over_flow_stress);
  r.check("closure_smax_over_flow_stress",
          f.closure.smax_over_flow_stress > 0.0 && f.closure.smax_over_flow_stress < 1.0,
          "must lie in (0, 1) (got " + core::format_number(f.closure.smax_over_flow_stress) + ")");
}

void read_fatigue(Context& ctx, const toml::table& t, const std::string& path, double horizon_ratio,
                  fatigue::FatigueSettings& f) {
  TableReader r(ctx, t, path);
  std::vector<std::pair<std::string_view, fatigue::FatigueLaw>> laws;
  for (const fatigue::LawEntry& e : fatigue::fatigue_laws()) laws.emplace_back(e.name, e.law);
  const auto law = r.choice<fatigue::FatigueLaw>("law", laws, std::nullopt);
  // Default φ0: the damage along a straight split at this horizon (000 Sec. 4.4's 0.398 at
  // δ = 3.015Δx). It discretizes a (2·ceil(ratio) + 4)² square with that horizon, so it is only
  // computed when phi0 is not given and the ratio is within its bounds (a bad horizon_ratio has
  // its own error): at horizon_ratio = 1000 it took 3.4 GB and 43 s.
  const bool default_computable =
      !r.has("phi0") && horizon_ratio >= kMinHorizonRatio && horizon_ratio <= kMaxHorizonRatio;
  const double default_phi0 = default_computable
                                  ? fatigue::phase_switch_damage_for_horizon(horizon_ratio)
                                  : fatigue::kPhaseSwitchDamage2D;
  f.phase_switch_damage = r.number("phi0", default_phi0);
  r.check("phi0", f.phase_switch_damage > 0 && f.phase_switch_damage < 1,
          "must lie in (0, 1) (got " + core::format_number(f.phase_switch_damage) + ")");
  if (!law) return;  // the allowed keys depend on the law: no unknown-key check
  f.law = *law;
  const fatigue::LawEntry& entry = fatigue::law_entry(*law);
  if (entry.static_failure) {
    std::vector<std::pair<std::string_view, fatigue::StaticFailure>> criteria;
    for (const auto& c : fatigue::static_failures()) criteria.emplace_back(c.name, c.criterion);
    f.static_failure =
        r.choice<fatigue::StaticFailure>("static_failure", criteria, f.static_failure)
            .value_or(f.static_failure);
  }
  TomlParamReader params(r);
  entry.read(params, f);
  read_compression(r, f);
  r.finish();
}

/// point = [x, y] | region = {...}; true when read.
bool read_target(Context& ctx, TableReader& r, const mesh::DetailGeometry& g, bool outline_ok,
                 NodeSelector& target) {
  const bool has_point = r.has("point");
  const bool has_region = r.has("region");
  if (has_point == has_region) {
    r.node("point", false);
    r.node("region", false);
    r.error(has_point ? "give either \"point\" or \"region\", not both"
                      : "missing required key \"point\" or \"region\"");
    return false;
  }
  if (has_point) {
    r.node("region", false);
    const auto p = r.point("point");
    if (!p) return false;
    if (outline_ok && !r.check("point", inside_outline(g.outline, *p), "lies outside the body")) {
      return false;
    }
    target = {NodeSelector::Kind::point, *p, {}};
    return true;
  }
  r.node("point", false);
  const toml::table* t = r.table("region", true);
  if (t == nullptr) return false;
  const auto region = read_region(ctx, *t, r.path_of("region"));
  if (region) target = {NodeSelector::Kind::region, {}, *region};
  return region.has_value();
}

void read_load(Context& ctx, const toml::table& t, const std::string& path,
               const mesh::DetailGeometry& g, bool outline_ok, std::vector<LoadSpec>& loads) {
  TableReader r(ctx, t, path);
  LoadSpec l;
  l.name = r.string("name", "");
  read_target(ctx, r, g, outline_ok, l.target);
  l.constant = r.point("constant", mesh::Point{});
  l.per_cos = r.point("per_cos", mesh::Point{});
  l.per_sin = r.point("per_sin", mesh::Point{});
  const bool zero = l.constant.x == 0 && l.constant.y == 0 && l.per_cos.x == 0 &&
                    l.per_cos.y == 0 && l.per_sin.x == 0 && l.per_sin.y == 0;
  if (zero) r.error("every force component is zero: give constant, per_cos or per_sin");
  l.where = ctx.ref(t, path);
  r.finish();
  loads.push_back(std::move(l));
}

void read_support(Context& ctx, const toml::table& t, const std::string& path,
                  const mesh::DetailGeometry& g, bool outline_ok,
                  std::vector<SupportSpec>& supports) {
  TableReader r(ctx, t, path);
  SupportSpec s;
  s.name = r.string("name", "");
  read_target(ctx, r, g, outline_ok, s.target);
  s.fix_x = r.boolean("fix_x", true);
  s.fix_y = r.boolean("fix_y", true);
  r.check(r.has("fix_y") ? "fix_y" : "fix_x", s.fix_x || s.fix_y,
          "fix_x and fix_y are both false: the support fixes nothing");
  s.where = ctx.ref(t, path);
  r.finish();
  supports.push_back(std::move(s));
}

void read_output(Context& ctx, const toml::table& t, const std::string& path, OutputConfig& o) {
  TableReader r(ctx, t, path);
  o.directory = r.string("directory", o.directory);
  r.check("directory", !o.directory.empty(), "must not be empty");
  o.field_every_batches = r.integer("field_every_batches", o.field_every_batches);
  r.check("field_every_batches", o.field_every_batches >= 0, "must be >= 0 (0 = never)");
  o.png = r.boolean("png", o.png);
  r.finish();
}

void read_spectrum_block(Context& ctx, const toml::table& t, const std::string& path,
                         std::vector<core::LoadBlock>& blocks) {
  TableReader r(ctx, t, path);
  core::LoadBlock b;
  const auto p_max = r.number("p_max");
  const auto ratio = r.number("r");
  b.alpha = r.number("alpha", 0.0);
  const auto count = r.integer("count");
  if (p_max && ratio && count) {
    b = {*p_max, *ratio, b.alpha, *count};
    // The one rule for a load block (core/load_block.h), named at the offending key.
    if (const core::Status valid = core::check_load_block(b); !valid) {
      r.check(valid.error().field, false, valid.error().reason);
    }
  }
  r.finish();
  blocks.push_back(b);
}

void read_life(Context& ctx, const toml::table& t, const std::string& path, const DetailConfig& d,
               LifeConfig& l) {
  TableReader r(ctx, t, path);
  const auto criterion = r.choice<LifeCriterion>("criterion",
                                                 {{"crack_length", LifeCriterion::crack_length},
                                                  {"phase3", LifeCriterion::phase3},
                                                  {"connectivity", LifeCriterion::connectivity}},
                                                 l.criterion);
  l.criterion = criterion.value_or(l.criterion);
  if (criterion == LifeCriterion::crack_length) {
    l.critical_crack_length = req(r, "critical_crack_length", core::Bound::positive).value_or(0.0);
    l.crack_origin = r.string("crack_origin", "");
  } else if (criterion) {
    for (const char* key : {"critical_crack_length", "crack_origin"}) {
      r.node(key, false);
      r.check(key, !r.has(key), "only used with criterion = \"crack_length\"");
    }
  } else {
    r.node("critical_crack_length", false);
    r.node("crack_origin", false);
  }
  if (const toml::node* n = r.node("reference_spectrum", false); n != nullptr && n->is_string()) {
    r.check("reference_spectrum", n->as_string()->get() == "empirical",
            "must be \"empirical\" or an array of blocks {p_max, r, alpha, count}");
  } else if (n != nullptr) {
    each_table(r, "reference_spectrum", true, "\"empirical\" or an array of blocks",
               [&](const auto& e, const auto& p) {
                 read_spectrum_block(ctx, e, p, l.reference_spectrum);
               });
  }
  l.every_batches = r.integer("every_batches", l.every_batches);
  r.check("every_batches", l.every_batches >= 0, "must be >= 0 (0 = never)");
  l.every_cycles = r.integer("every_cycles", l.every_cycles);
  r.check("every_cycles", l.every_cycles >= 0, "must be >= 0 (0 = never)");
  const auto band = r.choice<BandSource>(
      "band", {{"none", BandSource::none}, {"a2_scatter", BandSource::a2_scatter}}, l.band);
  l.band = band.value_or(l.band);
  if (band == BandSource::a2_scatter) {
    if (const auto s = r.number("a2_relative_scatter")) {
      l.a2_relative_scatter = *s;
      r.check("a2_relative_scatter", *s > 0 && *s < 1,
              "must lie in (0, 1) (got " + core::format_number(*s) + ")");
    }
  } else {
    r.node("a2_relative_scatter", false);
    r.check("a2_relative_scatter", !band || !r.has("a2_relative_scatter"),
            "only used with band = \"a2_scatter\"");
  }
  if (r.has("dx")) {
    // The coarser estimate model (twin/coarse_life.h): its A2 is calibrated, so a law
    // with an A2 is needed, and it must be coarser than the detail's own grid.
    if (const auto dx = req(r, "dx", core::Bound::positive)) {
      l.dx = *dx;
      if (r.check("dx", fatigue::law_entry(d.fatigue.law).calibrated_a2,
                  "a coarser estimate model calibrates A2: only with fatigue law "
                  "\"strain_range\" or \"energy\"") &&
          d.dx > 0) {
        r.check("dx", *dx > d.dx,
                "must be larger than [detail.grid] dx = " + core::format_number(d.dx) +
                    " m: the estimate model is a coarser grid (got " + core::format_number(*dx) +
                    ")");
      }
    }
  }
  r.finish();
}

void read_stress_intensity(Context& ctx, const toml::table& t, const std::string& path,
                           StressIntensityConfig& k) {
  TableReader r(ctx, t, path);
  const auto method =
      r.choice<StressIntensityMethod>("method",
                                      {{"extrapolation", StressIntensityMethod::extrapolation},
                                       {"compact_tension", StressIntensityMethod::compact_tension}},
                                      k.method);
  k.method = method.value_or(k.method);
  if (method == StressIntensityMethod::compact_tension) {
    k.width = req(r, "width", core::Bound::positive).value_or(0.0);
    if (const auto p = r.point("load_line")) k.load_line = *p;
  } else {
    for (const char* key : {"width", "load_line"}) {
      r.node(key, false);
      r.check(key, !method || !r.has(key), "only used with method = \"compact_tension\"");
    }
  }
  r.finish();
}

void read_checkpoint(Context& ctx, const toml::table& t, const std::string& path,
                     CheckpointConfig& c) {
  TableReader r(ctx, t, path);
  c.every_batches = r.integer("every_batches", c.every_batches);
  r.check("every_batches", c.every_batches >= 0, "must be >= 0 (0 = off)");
  c.every_seconds = opt(r, "every_seconds", c.every_seconds, core::Bound::non_negative);
  r.finish();
}

void read_limits(Context& ctx, const toml::table& t, const std::string& path, LimitsConfig& l) {
  TableReader r(ctx, t, path);
  if (r.has("max_p")) l.max_p = req(r, "max_p", core::Bound::positive);
  r.node("max_p", false);
  l.max_batch_seconds = opt(r, "max_batch_seconds", l.max_batch_seconds, core::Bound::positive);
  l.max_sources = r.integer("max_sources", l.max_sources);
  r.check("max_sources", l.max_sources >= 1,
          "must be >= 1 (got " + std::to_string(l.max_sources) + ")");
  l.max_rejects_per_second =
      opt(r, "max_rejects_per_second", l.max_rejects_per_second, core::Bound::positive);
  l.release_idle_factor = r.boolean("release_idle_factor", l.release_idle_factor);
  r.finish();
}

void read_sensor(Context& ctx, const toml::table& t, const std::string& path, SensorConfig& s) {
  TableReader r(ctx, t, path);
  s.scale = opt(r, "scale", s.scale, core::Bound::any);
  r.check("scale", s.scale != 0.0, "must be != 0 (P = scale * measured + offset)");
  s.offset = opt(r, "offset", s.offset, core::Bound::any);
  s.gate = opt(r, "gate", s.gate, core::Bound::non_negative);
  s.alpha_bin = opt(r, "alpha_bin", s.alpha_bin, core::Bound::non_negative);
  r.finish();
}

void read_gauge(Context& ctx, const toml::table& t, const std::string& path,
                const mesh::DetailGeometry& g, bool outline_ok, std::vector<GaugeConfig>& gauges) {
  TableReader r(ctx, t, path);
  GaugeConfig c;
  if (const auto id = r.string("id")) {
    c.id = *id;
    // The rule of a detail id (messages/channels.h): a gauge id is a CSV column header and a
    // JSON key, so the same short, unambiguous alphabet.
    if (r.check("id", messages::is_valid_detail_id(*id),
                "\"" + *id + "\" is not 1 to 32 characters from [A-Za-z0-9_-]")) {
      const bool repeated = std::any_of(gauges.begin(), gauges.end(),
                                        [&](const GaugeConfig& o) { return o.id == *id; });
      r.check("id", !repeated, "gauge \"" + *id + "\" is defined twice in this detail");
    }
  }
  if (const auto at = r.point("at")) {
    c.at = *at;
    if (outline_ok) r.check("at", g.is_material(*at), "lies outside the material");
  }
  c.angle = opt(r, "angle", c.angle, core::Bound::any);
  c.length = opt(r, "length", c.length, core::Bound::non_negative);
  c.noise = opt(r, "noise", c.noise, core::Bound::non_negative);
  c.identify = r.boolean("identify", c.identify);
  c.where = ctx.ref(t, path);
  r.finish();
  gauges.push_back(std::move(c));
}

/// `file` as written in the config, or joined to the config file's directory when relative; made
/// absolute (against the working directory) so that it names the same file from anywhere.
std::string resolve_path(const std::string& file, const std::string& config_file) {
  namespace fs = std::filesystem;
  fs::path p(file);
  if (p.is_relative()) p = fs::path(config_file).parent_path() / p;
  std::error_code ec;
  const fs::path absolute = fs::absolute(p, ec);
  return (ec ? p : absolute).lexically_normal().string();
}

/// Reads [auth]; key_file relative to the directory of the config file (ctx.file).
AuthConfig read_auth(Context& ctx, const toml::table& t, const std::string& path) {
  AuthConfig a;
  a.where = ctx.ref(t, path);
  TableReader r(ctx, t, path);
  if (const auto file = r.string("key_file")) {
    if (r.check("key_file", !file->empty(), "must not be empty") &&
        r.check("key_file", file->find('\0') == std::string::npos,
                "must not contain a NUL character")) {
      a.key_file = resolve_path(*file, ctx.file);
    }
  }
  const std::string id_rule = " is not a valid id: 1 to " +
                              std::to_string(messages::kMaxSourceIdLength) +
                              " printable ASCII characters without blanks";
  if (const toml::array* sources = r.array("sources", false)) {
    for (std::size_t i = 0; i < sources->size(); ++i) {
      const toml::node& n = (*sources)[i];
      const std::string element = r.path_of("sources") + "[" + std::to_string(i) + "]";
      const auto* s = n.as_string();
      if (s == nullptr) {
        ctx.error(n.source(), element,
                  "expected a string, got " + std::string(type_name(n.type())));
        continue;
      }
      const std::string& id = s->get();
      if (!is_valid_source_id(id)) {
        ctx.error(n.source(), element, "\"" + id + "\"" + id_rule);
      } else if (std::find(a.sources.begin(), a.sources.end(), id) != a.sources.end()) {
        ctx.error(n.source(), element, "\"" + id + "\" is listed twice");
      } else {
        a.sources.push_back(id);
      }
    }
  }
  a.daemon_key = r.string("daemon_key", a.daemon_key);
  r.check("daemon_key", is_valid_source_id(a.daemon_key), "\"" + a.daemon_key + "\"" + id_rule);
  r.finish();
  return a;
}

/// Source of `key` inside table `t` (the table's own source when absent).
const toml::source_region& source_of(const toml::table& t, std::string_view key) {
  const toml::node* n = t.get(key);
  return n != nullptr ? n->source() : t.source();
}

/// Reads a lognormal prior {median, cov} at `key` of [detail.uncertainty].
void read_prior(Context& ctx, TableReader& r, std::string_view key, LognormalPrior& prior) {
  const toml::table* t = r.table(key, false);
  if (t == nullptr) return;
  TableReader pr(ctx, *t, r.path_of(key));
  prior.median = pr.number("median", prior.median);
  pr.check("median", prior.median > 0, "must be > 0 (a lognormal median)");
  prior.cov = pr.number("cov", prior.cov);
  pr.check("cov", prior.cov >= 0 && prior.cov <= 3,
           "must lie in [0, 3] (the coefficient of variation; 0 = known)");
  pr.finish();
}

/// [detail.uncertainty] (issue 32).
void read_uncertainty(Context& ctx, const toml::table& t, const std::string& path,
                      const DetailConfig& d, UncertaintyConfig& u) {
  TableReader r(ctx, t, path);
  u.enabled = true;
  u.particles = r.integer("particles", u.particles);
  r.check("particles", u.particles >= 2 && u.particles <= 4096, "must lie in [2, 4096]");
  const std::int64_t seed = r.integer("seed", 1);
  r.check("seed", seed >= 0, "must be >= 0");
  u.seed = static_cast<std::uint64_t>(seed);
  u.a2.median = d.fatigue.strain.A2;
  read_prior(ctx, r, "a2", u.a2);
  if (r.has("a2")) {
    r.check("a2", fatigue::law_entry(d.fatigue.law).calibrated_a2,
            "an uncertain A2 needs fatigue law \"strain_range\" or \"energy\"");
  }
  read_prior(ctx, r, "load_scale", u.load_scale);
  if (const toml::array* a = r.array("percentiles", false)) {
    u.percentiles.clear();
    bool ok = !a->empty();
    for (const auto& e : *a) {
      const auto v = e.value<double>();
      ok = ok && v && *v > 0 && *v < 100 && (u.percentiles.empty() || *v > u.percentiles.back());
      if (v) u.percentiles.push_back(*v);
    }
    r.check("percentiles", ok, "must be a non-empty array of increasing numbers in (0, 100)");
  }
  u.horizon_cycles = r.number("horizon_cycles", u.horizon_cycles);
  r.check("horizon_cycles", u.horizon_cycles >= 0, "must be >= 0 (0 = not published)");
  u.resample_ess_fraction = r.number("resample_ess_fraction", u.resample_ess_fraction);
  r.check("resample_ess_fraction", u.resample_ess_fraction > 0 && u.resample_ess_fraction <= 1,
          "must lie in (0, 1]");
  if (r.has("dx")) {
    u.dx = r.number("dx", 0.0);
    r.check("dx", u.dx > d.dx, "must be > the grid's dx (the particles' coarser grid)");
    r.check("dx", fatigue::law_entry(d.fatigue.law).calibrated_a2,
            "a coarser grid for the particles needs fatigue law \"strain_range\" or \"energy\" "
            "(A2 rescaled by 000 Eq. 29)");
  }
  u.every_batches = r.integer("every_batches", u.every_batches);
  r.check("every_batches", u.every_batches >= 0, "must be >= 0 (0 = at observations only)");
  r.finish();
}

/// Reads one [[detail]]; `estimate` gets its resources when its geometry and grid are valid.
DetailConfig read_detail(Context& ctx, const toml::table& t, const std::string& path,
                         std::optional<ResourceEstimate>* estimate) {
  DetailConfig d;
  d.where = ctx.ref(t, path);
  TableReader r(ctx, t, path);
  if (const auto id = r.string("id")) {
    d.id = *id;
    if (r.check("id", messages::is_valid_detail_id(*id),
                "\"" + *id + "\" is not 1 to 32 characters from [A-Za-z0-9_-]")) {
      d.token = messages::detail_token(*id);
    }
  }
  d.description = r.string("description", "");
  bool outline_ok = false;
  if (const auto* g = r.table("geometry", true)) {
    outline_ok = read_geometry(ctx, *g, r.path_of("geometry"), d.geometry);
  }
  const mesh::Rectangle box = d.geometry.bounding_box();  // used only when the outline is valid
  bool sized = false;  // geometry and grid valid: the resources can be estimated
  if (const auto* g = r.table("grid", true)) {
    const std::size_t before_grid = ctx.errors.size();
    read_grid(ctx, *g, r.path_of("grid"), outline_ok ? &box : nullptr, d);
    sized = outline_ok && ctx.errors.size() == before_grid && d.geometry.validate().ok();
  }
  const std::size_t errors_before = ctx.errors.size();
  if (const auto* m = r.table("model", false)) read_model(ctx, *m, r.path_of("model"), d.model);
  if (const auto* m = r.table("material", true)) {
    read_material(ctx, *m, r.path_of("material"), d.material);
    if (ctx.errors.size() == errors_before) {
      if (std::string why = core::message_of(model::validate(d.material, d.model)); !why.empty()) {
        ctx.error(m->source(), r.path_of("material"), why);
      } else if (d.geometry.rigid_model == mesh::RigidModel::stiff_material &&
                 !d.geometry.rigid_regions.empty()) {
        // Issue 31: 000's stiff material is indefinite in the state-based model below ν ≈ 1/3.
        const std::string stiff = core::message_of(
            model::check_stiff_rigid_material(d.material, d.model, d.geometry.rigid_factor));
        if (!stiff.empty()) {
          const auto* g = t["geometry"].as_table();
          ctx.error(g != nullptr ? source_of(*g, "rigid_model") : m->source(),
                    r.path_of("geometry") + ".rigid_model", stiff);
        }
      }
    }
  }
  if (const auto* f = r.table("fatigue", true)) {
    read_fatigue(ctx, *f, r.path_of("fatigue"), d.horizon_ratio, d.fatigue);
    if (fatigue::law_entry(d.fatigue.law).damage_based &&
        d.model.kind != model::ModelKind::bond_based) {
      ctx.error(source_of(*f, "law"), r.path_of("fatigue") + ".law",
                "\"bilinear\" is a bond law (003): it needs model.kind = \"bond_based\"");
    }
  }
  each_table(
      r, "load", true, "an array of tables ([[detail.load]])",
      [&](const auto& e, const auto& p) { read_load(ctx, e, p, d.geometry, outline_ok, d.loads); });
  each_table(r, "support", true, "an array of tables ([[detail.support]])",
             [&](const auto& e, const auto& p) {
               read_support(ctx, e, p, d.geometry, outline_ok, d.supports);
             });
  d.output.directory = "results/" + d.id;
  if (const auto* o = r.table("output", false)) read_output(ctx, *o, r.path_of("output"), d.output);
  // Relative to the config file's directory, as [auth] key_file: where the results go must not
  // depend on where the daemon was started from.
  if (!d.output.directory.empty()) d.output.directory = resolve_path(d.output.directory, ctx.file);
  if (const auto* l = r.table("life", false)) read_life(ctx, *l, r.path_of("life"), d, d.life);
  if (const auto* k = r.table("stress_intensity", false)) {
    read_stress_intensity(ctx, *k, r.path_of("stress_intensity"), d.stress_intensity);
  }
  if (const auto* c = r.table("checkpoint", false)) {
    read_checkpoint(ctx, *c, r.path_of("checkpoint"), d.checkpoint);
  }
  if (const auto* l = r.table("limits", false)) read_limits(ctx, *l, r.path_of("limits"), d.limits);
  if (const auto* u = r.table("uncertainty", false)) {
    read_uncertainty(ctx, *u, r.path_of("uncertainty"), d, d.uncertainty);
  }
  if (const auto* s = r.table("sensor", false)) read_sensor(ctx, *s, r.path_of("sensor"), d.sensor);
  each_table(r, "gauge", false, "an array of tables ([[detail.gauge]])",
             [&](const auto& e, const auto& p) {
               read_gauge(ctx, e, p, d.geometry, outline_ok, d.gauges);
             });
  r.finish();
  if (sized) *estimate = estimate_resources(d);
  return d;
}

/// A detail whose resources were estimated, and where its [detail.grid] dx was written.
struct Sized {
  const toml::table* detail = nullptr;
  std::string path;  ///< "detail[i]"
  ResourceEstimate estimate;
};

/// "3720 nodes, 49875 bonds, 4 fatigue engines with a Cholesky factor of 6.6e+06 entries each".
std::string describe(const ResourceEstimate& e) {
  return format_count(e.nodes) + " nodes, " + format_count(e.bonds) + " bonds, " +
         std::to_string(e.engines) + (e.engines == 1 ? " fatigue engine" : " fatigue engines") +
         " with a Cholesky factor of " + format_count(e.factor_nonzeros) + " entries" +
         (e.engines == 1 ? "" : " each");
}

/// The error at detail[i].grid.dx.
void refuse(Context& ctx, const Sized& s, std::string reason) {
  const toml::table* grid = s.detail->get_as<toml::table>("grid");
  const toml::source_region& where = grid != nullptr ? source_of(*grid, "dx") : s.detail->source();
  ctx.error(where, s.path + ".grid.dx", std::move(reason));
}

/// The resource bounds (config.h, "Resource bounds"): per detail the memory limit, else the
/// solver's 32-bit indices; then, if no detail was refused, all details together (named at the
/// largest).
void check_resources(Context& ctx, const std::vector<Sized>& sized) {
  const std::string remedy =
      ": use a larger dx (nodes grow as 1/dx², the factor as log(1/dx)/dx²) or a smaller "
      "horizon_ratio";
  const double limit = static_cast<double>(ctx.max_memory_bytes);
  const std::string limit_text =
      format_bytes(limit) + (ctx.default_memory_limit
                                 ? " (the default, 75 % of physical memory; --max-memory sets it)"
                                 : " (--max-memory)");
  bool refused = false;
  double total = 0.0;
  const Sized* largest = nullptr;
  // Each detail's live engine and model, plus the life engines of at most
  // concurrent_life_estimates details at once (the largest; every detail's when 0).
  std::vector<double> life_bytes;
  for (const Sized& s : sized) {
    const ResourceEstimate& e = s.estimate;
    const double life = (e.engines - 1) * e.engine_bytes;
    total += e.bytes - life;
    life_bytes.push_back(life);
    if (largest == nullptr || e.bytes > largest->estimate.bytes) largest = &s;
    const double index =
        std::max({2.0 * e.bonds, e.unknowns, e.matrix_nonzeros, e.factor_nonzeros});
    if (ctx.max_memory_bytes > 0 && e.bytes > limit) {
      refuse(ctx, s,
             "the detail would need an estimated " + format_bytes(e.bytes) + " (" + describe(e) +
                 "), more than the memory limit " + limit_text + remedy + ", or raise the limit");
      refused = true;
    } else if (index > kMaxSolverIndex) {
      refuse(ctx, s,
             "the detail is too large for the solver's 32-bit indices (at most " +
                 format_count(kMaxSolverIndex) + " entries): estimated " + describe(e) + remedy);
      refused = true;
    }
  }
  std::sort(life_bytes.begin(), life_bytes.end(), std::greater<>());
  const std::size_t estimating =
      ctx.concurrent_life_estimates > 0
          ? std::min(life_bytes.size(), static_cast<std::size_t>(ctx.concurrent_life_estimates))
          : life_bytes.size();
  for (std::size_t i = 0; i < estimating; ++i) total += life_bytes[i];
  if (!refused && largest != nullptr && ctx.max_memory_bytes > 0 && total > limit) {
    const std::string at_once = ctx.concurrent_life_estimates > 0
                                    ? " (remaining-life simulations of at most " +
                                          std::to_string(ctx.concurrent_life_estimates) +
                                          " detail(s) at once)"
                                    : "";
    refuse(ctx, *largest,
           "the " + std::to_string(sized.size()) + " details would need an estimated " +
               format_bytes(total) + " together" + at_once + ", more than the memory limit " +
               limit_text + "; this, the largest, needs " + format_bytes(largest->estimate.bytes) +
               " (" + describe(largest->estimate) + ")" + remedy + ", or raise the limit");
  }
}

}  // namespace

/// Whether this process serves detail `id` (ConfigLimits::served_details).
bool served(const Context& ctx, const std::string& id) {
  return ctx.served_details.empty() ||
         std::find(ctx.served_details.begin(), ctx.served_details.end(), id) !=
             ctx.served_details.end();
}

TwinConfig parse_document(Context& ctx, const toml::table& root) {
  TwinConfig config;
  TableReader r(ctx, root, "");
  std::map<std::string, std::size_t> tokens;       // channel token -> first detail
  std::map<std::string, std::size_t> directories;  // output directory -> first detail
  std::vector<Sized> sized;                        // details whose resources were estimated
  each_table(r, "detail", true, "an array of tables ([[detail]])",
             [&](const toml::table& t, const std::string& path) {
               const std::size_t i = config.details.size();
               std::optional<ResourceEstimate> estimate;
               DetailConfig d = read_detail(ctx, t, path, &estimate);
               if (estimate && served(ctx, d.id)) sized.push_back({&t, path, *estimate});
               if (!d.token.empty()) {
                 const auto [it, fresh] = tokens.emplace(d.token, i);
                 if (!fresh) {
                   const auto& first = config.details[it->second];
                   ctx.error(source_of(t, "id"), path + ".id",
                             "\"" + d.id + "\" has the same channel token " + d.token +
                                 " as detail[" + std::to_string(it->second) + "] (\"" + first.id +
                                 "\", line " + std::to_string(first.where.line) + ")");
                 }
               }
               const auto [it, fresh] = directories.emplace(d.output.directory, i);
               if (!fresh && !d.id.empty()) {
                 const auto* out = t.get_as<toml::table>("output");
                 ctx.error(out != nullptr ? source_of(*out, "directory") : t.source(),
                           path + ".output.directory",
                           "\"" + d.output.directory +
                               "\" is also the output directory of detail[" +
                               std::to_string(it->second) + "]");
               }
               config.details.push_back(std::move(d));
             });
  if (const auto* a = r.table("auth", false)) config.auth = read_auth(ctx, *a, "auth");
  r.finish();
  check_resources(ctx, sized);
  if (!ctx.served_details.empty()) {
    // A fleet sharing one config: this process serves the listed details only.
    std::string ids;
    for (const auto& d : config.details) ids += (ids.empty() ? "" : ", ") + d.id;
    for (const std::string& id : ctx.served_details) {
      if (std::none_of(config.details.begin(), config.details.end(),
                       [&](const DetailConfig& d) { return d.id == id; })) {
        ctx.errors.push_back({ctx.file, 0, 0, "--details",
                              "no detail \"" + id + "\" in the file (its details: " + ids + ")"});
      }
    }
    std::erase_if(config.details, [&](const DetailConfig& d) { return !served(ctx, d.id); });
  }
  return config;
}

}  // namespace peritwin::config::config_internal
