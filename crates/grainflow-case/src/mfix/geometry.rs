//! The STL walls of an MFIX deck's cut-cell boundaries, from the solver's files or from the
//! GUI's `#!MFIX-GUI` project data.
//!
//! # Where MFIX 21.3.2 takes the facets from
//! The solver (`model/cartesian_grid/get_stl_data.f`, `GET_STL_DATA`) reads, for every
//! boundary whose `BC_TYPE` starts with `CG_`, the file `geometry_NNNN.stl` (NNNN = the BC id,
//! four digits) from the run folder, and gives each of its facets that BC's id
//! (`BC_ID_STL_FACE`); a missing file stops the run. It moves the vertices by
//! `SCALE_STL·v + TX_STL` (…`TY_STL`, `TZ_STL`) and turns the normals round where
//! `FLIP_STL_NORMALS(bc)` is set or `OUT_STL_VALUE = -1`; a plain `geometry.stl` is not read
//! by this version. The GUI writes those files when it saves a project
//! (`mfixgui/vtk_widgets/geometry_engine.py`, `export_stl`): `geometry.stl` holds all visible
//! top-level geometry, and `geometry_NNNN.stl` the facets of each BC whose region has
//! `"type": "STL"`, already transformed into place (`select_facets`: the union of the
//! region's `geometry_pool` nodes, kept whole when the region's `stl_shape` is `"all"`, the
//! default, else cut to the region's box or ellipsoid, and optionally filtered by the
//! facets' normals).
//!
//! [`stl_walls`] therefore prefers, in this order: the `geometry_NNNN.stl` files beside the
//! deck (as the solver reads them; [`StlWall::from_solver_file`], so the caller applies
//! `SCALE_STL`/`TX_STL`); `geometry.stl` when there is one BC to give it to, or no GUI
//! geometry (then one wall, given to the first BC: an older solver's single file, all facets
//! one wall); else the GUI's project data, each STL node of the region's pool one wall, with
//! the GUI's transform rewritten as grainflow's (below).
//!
//! # The GUI's transform of an STL node
//! `GeometryEngine.update_transform` builds a VTK transform in post-multiply order: translate
//! by −c (c = `centerx/y/z`, the mean of the file's points, which the GUI recomputes on every
//! load), scale by `scale` (uniform; `units` only sets `scale`), rotate by `rotationx`, then
//! `rotationy`, then `rotationz` degrees about the x, y, z axes (`RotateWXYZ`: right hand),
//! translate by +c, then by `translationx/y/z`. With `aboutorigin: true` (set when the GUI
//! took over a deck's `TX_STL`/`SCALE_STL`) both centre steps are left out. So
//! p′ = R·(s·(p − c)) + c + T, R = Rz·Ry·Rx: grainflow's mesh transform p′ = R·(s·p) + t with
//! the same s and rotations and t = T + c − R·(s·c), exact. `flipnormals` reverses the cells
//! before the transform (`vtkReverseSense`), which commutes with it (s > 0).
//!
//! # Normals
//! MFIX's facets face the fluid, i.e. the particles: the tutorials' `hopper.stl` has every
//! winding normal pointing into the hopper and no flip, while `drum.stl` is a closed cylinder
//! wound outwards (positive enclosed volume) and carries `flipnormals: true`, which turns it
//! towards the particles inside. grainflow's triangle normals also point to the particles'
//! side (docs/case-file.md, `[[meshes]]`: `flip_normals` is for "a file whose normals point
//! away from the particles"), so the GUI's `flipnormals` maps onto `flip_normals` unchanged.
//!
//! # Refused
//! Geometry nodes other than STL files (primitives, implicits, parametric and procedural
//! shapes, filters, booleans: a boolean union of meshes trims them, which a list of mesh walls
//! cannot say), regions that cut or filter their facets, a node reading `geometry.stl` (the
//! GUI reads `geometry.stl.original` in its place), a non-positive scale, and a centre the
//! GUI would have to compute. The message names the node or region; saving the project in
//! the GUI writes the `geometry_NNNN.stl` files, which are always read.

use super::lexer::Loc;
use serde_json::Value;

/// One mesh wall of a cut-cell boundary.
#[derive(Debug, Clone, PartialEq)]
pub struct StlWall {
    /// The BC id whose facets these are.
    pub bc: i64,
    /// A name for messages: the region's (with the node's when the region has several), or
    /// the file's.
    pub name: String,
    /// The STL file, relative to the deck's folder (or absolute, as the GUI wrote it).
    pub file: String,
    /// Uniform scale, applied first.
    pub scale: f64,
    /// Rotations about x, then y, then z, degrees, right hand, about the origin.
    pub rotate: [f64; 3],
    /// Translation, applied last.
    pub translate: [f64; 3],
    /// Reverse every triangle's winding (the GUI's `flipnormals`).
    pub flip_normals: bool,
    /// The file is one the solver reads (`geometry_NNNN.stl`, `geometry.stl`): the deck's
    /// `SCALE_STL` and `TX_STL`/`TY_STL`/`TZ_STL` still apply to it (the transform here is the
    /// identity).
    pub from_solver_file: bool,
}

/// The last `#!MFIX-GUI key = …` comment of that key (the GUI keeps the last one).
fn gui_entry<'a>(gui: &'a [(String, String, Loc)], key: &str) -> Option<&'a (String, String, Loc)> {
    let key = key.to_ascii_lowercase();
    gui.iter().rev().find(|(k, _, _)| *k == key)
}

/// The value of the GUI comment `key` parsed as JSON: `None` when there is no such comment,
/// an error (with its line) when it is not valid JSON.
pub fn gui_json(gui: &[(String, String, Loc)], key: &str) -> Option<Result<Value, String>> {
    let (k, text, loc) = gui_entry(gui, key)?;
    Some(
        serde_json::from_str(text)
            .map_err(|e| format!("{loc}: the GUI's `#!MFIX-GUI {k} = …` is not valid JSON ({e})")),
    )
}

/// The STL walls of the boundaries `bcs` (the `CG_` BC ids), as described in the
/// [module doc](self). `exists` tells whether a file (relative to the deck's folder) is there.
pub fn stl_walls(
    gui: &[(String, String, Loc)],
    bcs: &[i64],
    exists: &dyn Fn(&str) -> bool,
) -> Result<Vec<StlWall>, String> {
    if bcs.is_empty() {
        return Ok(Vec::new());
    }
    let files: Vec<String> = bcs.iter().map(|b| format!("geometry_{b:04}.stl")).collect();
    if let Some(found) = files.iter().find(|f| exists(f)) {
        let mut walls = Vec::new();
        for (&bc, file) in bcs.iter().zip(&files) {
            if !exists(file) {
                return Err(format!(
                    "{file} (the facets of BC {bc}, a CG_ boundary) is missing beside the deck, though {found} is there: MFIX reads one geometry_NNNN.stl per CG_ boundary and stops without it"
                ));
            }
            walls.push(solver_wall(bc, format!("BC {bc}"), file.clone()));
        }
        return Ok(walls);
    }
    let have_gui = gui_entry(gui, "geometry").is_some();
    if exists("geometry.stl") && (bcs.len() == 1 || !have_gui) {
        let name = if bcs.len() == 1 {
            format!("BC {}", bcs[0])
        } else {
            let ids: Vec<String> = bcs.iter().map(i64::to_string).collect();
            format!("BC {} (geometry.stl, all of BCs {})", bcs[0], ids.join(", "))
        };
        return Ok(vec![solver_wall(bcs[0], name, "geometry.stl".to_string())]);
    }
    if !have_gui {
        return Err(format!(
            "no STL file for the CG_ boundaries: MFIX reads {} beside the deck, and there is neither these, nor geometry.stl, nor the GUI's `#!MFIX-GUI geometry` comment",
            files.join(", ")
        ));
    }
    from_gui(gui, bcs, exists)
}

/// The STL facets of the internal surfaces `ids` (`IS_TYPE = 'STL'`): `is_NNNN.stl` beside
/// the deck, as MFIX's solver reads them, else the files the GUI's `is_regions` name. Each
/// wall's `bc` is the internal surface's id.
pub fn is_walls(
    gui: &[(String, String, Loc)],
    ids: &[i64],
    exists: &dyn Fn(&str) -> bool,
) -> Result<Vec<StlWall>, String> {
    let mut walls = Vec::new();
    let mut from_gui_ids = Vec::new();
    for &id in ids {
        let file = format!("is_{id:04}.stl");
        if exists(&file) {
            walls.push(solver_wall(id, format!("IS {id}"), file));
        } else {
            from_gui_ids.push(id);
        }
    }
    if !from_gui_ids.is_empty() {
        walls.extend(from_gui_regions(gui, &from_gui_ids, exists, "is_regions", "IS")?);
    }
    Ok(walls)
}

/// A wall of one of the solver's own files, placed as it is (MFIX's SCALE_STL and TX_STL …
/// apply to it).
fn solver_wall(bc: i64, name: String, file: String) -> StlWall {
    StlWall {
        bc,
        name,
        file,
        scale: 1.0,
        rotate: [0.0; 3],
        translate: [0.0; 3],
        flip_normals: false,
        from_solver_file: true,
    }
}

/// A GUI comment that must be there, as JSON.
fn need_json(gui: &[(String, String, Loc)], key: &str) -> Result<Value, String> {
    gui_json(gui, key).unwrap_or_else(|| {
        Err(format!("the GUI's `#!MFIX-GUI {key} = …` comment, which says which geometry each boundary has, is missing"))
    })
}

/// The walls from the GUI's `bc_regions`, `regions_dict` and `geometry`.
fn from_gui(
    gui: &[(String, String, Loc)],
    bcs: &[i64],
    exists: &dyn Fn(&str) -> bool,
) -> Result<Vec<StlWall>, String> {
    from_gui_regions(gui, bcs, exists, "bc_regions", "BC")
}

/// [`from_gui`] for the regions of `key` (`bc_regions`, `is_regions`), whose ids are named
/// `label` in messages.
fn from_gui_regions(
    gui: &[(String, String, Loc)],
    bcs: &[i64],
    exists: &dyn Fn(&str) -> bool,
    key: &str,
    label: &str,
) -> Result<Vec<StlWall>, String> {
    let geometry = need_json(gui, "geometry")?;
    let regions = need_json(gui, "regions_dict")?;
    let bc_regions = need_json(gui, key)?;
    let params = match gui_json(gui, "parameters") {
        Some(p) => p?,
        None => Value::Null,
    };
    let eval = Eval { params: params.get("parameters").unwrap_or(&Value::Null), depth: 0 };
    let geo_loc = gui_entry(gui, "geometry").map(|e| e.2.to_string()).unwrap_or_default();

    // bc_regions: [[[ids…], [regions…]], …], the k-th id with the k-th region.
    let mut region_of: Vec<(i64, String)> = Vec::new();
    for row in bc_regions.as_array().into_iter().flatten() {
        let (Some(ids), Some(names)) =
            (row.get(0).and_then(Value::as_array), row.get(1).and_then(Value::as_array))
        else {
            return Err(format!("the GUI's `{key}` entry {row} is not [[ids], [regions]]"));
        };
        for (id, name) in ids.iter().zip(names) {
            if let (Some(id), Some(name)) = (id.as_i64(), name.as_str()) {
                region_of.push((id, name.to_string()));
            }
        }
    }
    let dict = geometry.get("geometry_dict").and_then(Value::as_object);
    let mut walls = Vec::new();
    for &bc in bcs {
        let Some((_, region)) = region_of.iter().find(|(id, _)| *id == bc) else {
            return Err(format!(
                "{label} {bc} has no region in the GUI's `{key}`, and its STL file is not beside the deck"
            ));
        };
        let Some(data) = regions.get("regions").and_then(|r| r.get(region)) else {
            return Err(format!(
                "the region \"{region}\" of {label} {bc} is not in the GUI's `regions_dict`"
            ));
        };
        let kind = data.get("type").and_then(Value::as_str).unwrap_or("box");
        if !kind.eq_ignore_ascii_case("stl") {
            return Err(format!(
                "{label} {bc} needs STL geometry, but its region \"{region}\" is of type \"{kind}\", not \"STL\""
            ));
        }
        let shape = data.get("stl_shape").and_then(Value::as_str).unwrap_or("all");
        if !shape.eq_ignore_ascii_case("all") {
            return Err(format!(
                "the region \"{region}\" of {label} {bc} keeps only the facets inside its {shape} (stl_shape), which grainflow cannot cut; save the project in the MFIX GUI so that it writes geometry_{bc:04}.stl, which is read instead"
            ));
        }
        if data.get("filter_facets").and_then(Value::as_bool).unwrap_or(false) {
            return Err(format!(
                "the region \"{region}\" of {label} {bc} filters its facets by their normals (filter_facets), which grainflow cannot do; save the project in the MFIX GUI so that it writes geometry_{bc:04}.stl, which is read instead"
            ));
        }
        let pool: Vec<&str> = data
            .get("geometry_pool")
            .and_then(Value::as_array)
            .map(|p| p.iter().filter_map(Value::as_str).collect())
            .unwrap_or_default();
        if pool.is_empty() {
            return Err(format!(
                "the STL region \"{region}\" of {label} {bc} names no geometry (its geometry_pool is empty)"
            ));
        }
        for &node in &pool {
            let Some(geo) = dict.and_then(|d| d.get(node)) else {
                return Err(format!(
                    "{geo_loc}: the geometry \"{node}\" of region \"{region}\" ({label} {bc}) is not in the GUI's `geometry`"
                ));
            };
            let name = if pool.len() == 1 { region.clone() } else { format!("{region}: {node}") };
            let mut wall = stl_node(node, geo, &eval).map_err(|e| format!("{geo_loc}: {e}"))?;
            if !exists(&wall.file) {
                return Err(format!(
                    "{geo_loc}: the STL file {} of geometry \"{node}\" (region \"{region}\", {label} {bc}) is not beside the deck (names are case-sensitive, as for the GUI)",
                    wall.file
                ));
            }
            wall.bc = bc;
            wall.name = name;
            walls.push(wall);
        }
    }
    Ok(walls)
}

/// One `geo_type: "stl"` node of the GUI's `geometry_dict` as a wall (bc and name left blank).
fn stl_node(node: &str, geo: &Value, eval: &Eval<'_>) -> Result<StlWall, String> {
    let geo_type = geo.get("geo_type").and_then(Value::as_str).unwrap_or("?");
    if geo_type != "stl" {
        let what = geo.get("type").and_then(Value::as_str).unwrap_or(geo_type);
        return Err(format!(
            "the geometry \"{node}\" is a {geo_type} ({what}) of the GUI's modeller; grainflow reads only STL files: save the project in the MFIX GUI so that it writes the geometry_NNNN.stl files, which are read instead"
        ));
    }
    let num = |key: &str, default: f64| -> Result<f64, String> {
        match geo.get(key) {
            None | Some(Value::Null) => Ok(default),
            Some(v) => eval
                .value(v)
                .map_err(|e| format!("the geometry \"{node}\"'s {key} ({v}) cannot be read: {e}")),
        }
    };
    let Some(filename) = geo.get("filename").and_then(Value::as_str) else {
        return Err(format!("the geometry \"{node}\" has no filename"));
    };
    let file = filename
        .strip_prefix("${proj_dir}/")
        .or_else(|| filename.strip_prefix("${proj_dir}\\"))
        .unwrap_or(filename)
        .to_string();
    if file.rsplit(['/', '\\']).next() == Some("geometry.stl") {
        return Err(format!(
            "the geometry \"{node}\" reads geometry.stl, which the GUI overwrites when it saves (it reads geometry.stl.original instead): rename the file"
        ));
    }
    let s = num("scale", 1.0)?;
    if !(s.is_finite() && s > 0.0) {
        return Err(format!("the geometry \"{node}\"'s scale {s} is not a positive number"));
    }
    let rotate = [num("rotationx", 0.0)?, num("rotationy", 0.0)?, num("rotationz", 0.0)?];
    let shift = [num("translationx", 0.0)?, num("translationy", 0.0)?, num("translationz", 0.0)?];
    let about_origin = truthy(geo.get("aboutorigin"));
    let moves_centre = !about_origin && (s != 1.0 || rotate != [0.0; 3]);
    let centre = if moves_centre {
        let mut c = [0.0; 3];
        for (k, key) in ["centerx", "centery", "centerz"].into_iter().enumerate() {
            if geo.get(key).is_none() {
                return Err(format!(
                    "the geometry \"{node}\" is scaled or rotated about its centre, but its {key} is not given (the GUI computes it from the file)"
                ));
            }
            c[k] = num(key, 0.0)?;
        }
        c
    } else {
        [0.0; 3]
    };
    // t = T + c − R·(s·c)
    let rc = rotate_xyz(rotate, centre.map(|x| s * x));
    let translate = [0, 1, 2].map(|k| shift[k] + (centre[k] - rc[k]));
    Ok(StlWall {
        bc: 0,
        name: String::new(),
        file,
        scale: s,
        rotate,
        translate,
        flip_normals: truthy(geo.get("flipnormals")),
        from_solver_file: false,
    })
}

/// Python's truth of a JSON flag as the GUI reads it (`safe_int`): true, or a non-zero number.
fn truthy(v: Option<&Value>) -> bool {
    match v {
        Some(Value::Bool(b)) => *b,
        Some(Value::Number(n)) => n.as_f64().is_some_and(|x| x != 0.0),
        Some(Value::String(s)) => s.trim().parse::<f64>().is_ok_and(|x| x != 0.0) || s.trim() == "True",
        _ => false,
    }
}

/// Rotates `p` about x, then y, then z by `deg` degrees (right hand), as grainflow's meshes and
/// VTK's `RotateWXYZ` in post-multiply order do.
fn rotate_xyz(deg: [f64; 3], p: [f64; 3]) -> [f64; 3] {
    let mut p = p;
    for (axis, d) in deg.into_iter().enumerate() {
        if d == 0.0 {
            continue;
        }
        let (s, c) = d.to_radians().sin_cos();
        let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
        let (a, b) = (p[i], p[j]);
        p[i] = c * a - s * b;
        p[j] = s * a + c * b;
    }
    p
}

/// Numbers of the GUI's JSON: plain numbers, or `{"__type__": "equation", "eq": "…"}` with
/// `+ - * / **`, parentheses, `float(…)`/`int(…)`, numbers and the project's `parameters`.
struct Eval<'a> {
    params: &'a Value,
    depth: usize,
}

impl Eval<'_> {
    fn value(&self, v: &Value) -> Result<f64, String> {
        if self.depth > 16 {
            return Err("parameters refer to each other too deeply".into());
        }
        match v {
            Value::Number(n) => n.as_f64().ok_or_else(|| "not a number".to_string()),
            Value::String(s) => s.trim().parse().map_err(|_| format!("\"{s}\" is not a number")),
            Value::Object(o) if o.get("__type__").and_then(Value::as_str) == Some("equation") => {
                let eq = o.get("eq").and_then(Value::as_str).ok_or("an equation without `eq`")?;
                let toks = tokens(eq)?;
                let mut p = Parser { toks: &toks, at: 0, eval: self };
                let x = p.sum()?;
                if p.at != toks.len() {
                    return Err(format!("cannot evaluate the equation `{eq}`"));
                }
                Ok(x)
            }
            _ => Err("not a number or an equation".into()),
        }
    }

    fn param(&self, name: &str) -> Result<f64, String> {
        let v = self.params.get(name).ok_or_else(|| format!("unknown parameter `{name}`"))?;
        Eval { params: self.params, depth: self.depth + 1 }.value(v)
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Num(f64),
    Name(String),
    Op(&'static str),
}

fn tokens(eq: &str) -> Result<Vec<Tok>, String> {
    let c: Vec<char> = eq.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch.is_ascii_digit() || ch == '.' {
            let start = i;
            while i < c.len()
                && (c[i].is_ascii_digit()
                    || c[i] == '.'
                    || c[i] == 'e'
                    || c[i] == 'E'
                    || ((c[i] == '+' || c[i] == '-') && matches!(c[i - 1], 'e' | 'E')))
            {
                i += 1;
            }
            let s: String = c[start..i].iter().collect();
            out.push(Tok::Num(s.parse().map_err(|_| format!("bad number `{s}` in `{eq}`"))?));
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(Tok::Name(c[start..i].iter().collect()));
        } else {
            let op = match ch {
                '*' if c.get(i + 1) == Some(&'*') => "**",
                '+' => "+",
                '-' => "-",
                '*' => "*",
                '/' => "/",
                '(' => "(",
                ')' => ")",
                _ => return Err(format!("cannot evaluate `{eq}` (at `{ch}`)")),
            };
            i += op.len();
            out.push(Tok::Op(op));
        }
    }
    Ok(out)
}

struct Parser<'a> {
    toks: &'a [Tok],
    at: usize,
    eval: &'a Eval<'a>,
}

impl Parser<'_> {
    fn eat(&mut self, op: &str) -> bool {
        if matches!(self.toks.get(self.at), Some(Tok::Op(o)) if *o == op) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    fn sum(&mut self) -> Result<f64, String> {
        let mut x = self.product()?;
        loop {
            if self.eat("+") {
                x += self.product()?;
            } else if self.eat("-") {
                x -= self.product()?;
            } else {
                return Ok(x);
            }
        }
    }

    fn product(&mut self) -> Result<f64, String> {
        let mut x = self.unary()?;
        loop {
            if self.eat("*") {
                x *= self.unary()?;
            } else if self.eat("/") {
                x /= self.unary()?;
            } else {
                return Ok(x);
            }
        }
    }

    fn unary(&mut self) -> Result<f64, String> {
        if self.eat("-") {
            return Ok(-self.unary()?);
        }
        if self.eat("+") {
            return self.unary();
        }
        let base = self.atom()?;
        // Python: ** binds tighter than unary minus on its left and is right-associative.
        if self.eat("**") { Ok(base.powf(self.unary()?)) } else { Ok(base) }
    }

    fn atom(&mut self) -> Result<f64, String> {
        match self.toks.get(self.at).cloned() {
            Some(Tok::Num(x)) => {
                self.at += 1;
                Ok(x)
            }
            Some(Tok::Name(n)) => {
                self.at += 1;
                if self.eat("(") {
                    let x = self.sum()?;
                    if !self.eat(")") {
                        return Err("a `(` without its `)`".into());
                    }
                    match n.as_str() {
                        "float" => Ok(x),
                        "int" => Ok(x.trunc()),
                        _ => Err(format!("unknown function `{n}`")),
                    }
                } else {
                    self.eval.param(&n)
                }
            }
            Some(Tok::Op("(")) => {
                self.at += 1;
                let x = self.sum()?;
                if self.eat(")") { Ok(x) } else { Err("a `(` without its `)`".into()) }
            }
            _ => Err("an incomplete equation".into()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mfix::lexer::lex_deck;

    fn gui(text: &str) -> Vec<(String, String, Loc)> {
        lex_deck(text, "t.mfx").unwrap().gui
    }

    fn only<'a>(files: &'a [&'a str]) -> impl Fn(&str) -> bool + 'a {
        move |f| files.contains(&f)
    }

    const DRUM: &str = "\
run_name = 'd'
#!MFIX-GUI regions_dict = {\"order\": [\"shell\", \"side\"], \"regions\": {\"shell\":
#!MFIX-GUI   {\"to\": [1, 1, 1], \"from\": [0, 0, 0], \"geometry_pool\": [\"tube.stl\"],
#!MFIX-GUI   \"type\": \"STL\"}, \"side\": {\"type\": \"XZ-plane\"}}}
#!MFIX-GUI geometry = {\"geometry_dict\": {\"tube.stl\": {\"geo_type\": \"stl\",
#!MFIX-GUI   \"filename\": \"${proj_dir}/Tube.stl\", \"centerx\": 0.0, \"centery\": 0.0,
#!MFIX-GUI   \"centerz\": 0.5, \"translationy\": 0.25, \"flipnormals\": true}}, \"tree\":
#!MFIX-GUI   {\"tube.stl\": []}}
#!MFIX-GUI bc_regions = [[[1], [\"shell\"]], [[2], [\"side\"]]]
";

    #[test]
    fn continuation_lines_join_the_previous_value() {
        let g = gui(
            "#!MFIX-GUI a = {\"x\": \"p = q\",\n#!MFIX-GUI   \"y\": [1,\n#!MFIX-GUI     2]}\n#!MFIX-GUI b = two words\nx_min = 0\n#!MFIX-GUI   orphan? no: joins b\n",
        );
        assert_eq!(g.len(), 2);
        assert_eq!(g[0].0, "a");
        assert_eq!(g[0].1, "{\"x\": \"p = q\", \"y\": [1, 2]}");
        assert_eq!(g[0].2, Loc::Line { file: "t.mfx".into(), line: 1 });
        assert_eq!(g[1].1, "two words orphan? no: joins b");
        let v = gui_json(&g, "A").unwrap().unwrap();
        assert_eq!(v["y"][1], 2);
        assert!(gui_json(&g, "missing").is_none());
        let bad = gui("#!MFIX-GUI c = {\"open\": \n");
        assert!(gui_json(&bad, "c").unwrap().unwrap_err().contains("t.mfx, line 1"));
        // A wrapped string value (the GUI wraps at blanks) gets its blank back.
        let g = gui("#!MFIX-GUI bc_regions = [[[4], [\"bottom\n#!MFIX-GUI   belt\"]]]\n");
        assert_eq!(gui_json(&g, "bc_regions").unwrap().unwrap()[0][1][0], "bottom belt");
    }

    #[test]
    fn drum_like_single_stl_with_a_translation() {
        let g = gui(DRUM);
        let walls = stl_walls(&g, &[1], &only(&["Tube.stl"])).unwrap();
        assert_eq!(
            walls,
            vec![StlWall {
                bc: 1,
                name: "shell".into(),
                file: "Tube.stl".into(),
                scale: 1.0,
                rotate: [0.0; 3],
                translate: [0.0, 0.25, 0.0],
                flip_normals: true,
                from_solver_file: false,
            }]
        );
        // The file's name is the `filename`'s, case and all: the node's lower-cased name is
        // not a file.
        let err = stl_walls(&g, &[1], &only(&["tube.stl"])).unwrap_err();
        assert!(err.contains("Tube.stl") && err.contains("line 5"), "{err}");
        // A CG_ boundary whose region is a plane is refused.
        let err = stl_walls(&g, &[1, 2], &only(&["Tube.stl"])).unwrap_err();
        assert!(err.contains("\"side\"") && err.contains("XZ-plane"), "{err}");
    }

    #[test]
    fn conveyor_like_three_stls() {
        let text = "\
#!MFIX-GUI regions_dict = {\"regions\": {\"box\": {\"geometry_pool\": [\"box.stl\"], \"type\": \"STL\"},
#!MFIX-GUI   \"upper belt\": {\"geometry_pool\": [\"up.stl\"], \"type\": \"STL\"}, \"lower belt\":
#!MFIX-GUI   {\"geometry_pool\": [\"down.stl\"], \"type\": \"STL\"}, \"out\": {\"type\": \"YZ-plane\"}}}
#!MFIX-GUI geometry = {\"geometry_dict\": {\"up.stl\": {\"geo_type\": \"stl\", \"filename\":
#!MFIX-GUI   \"${proj_dir}/Up.stl\", \"centerx\": 1.0}, \"down.stl\": {\"geo_type\": \"stl\",
#!MFIX-GUI   \"filename\": \"${proj_dir}/Down.stl\"}, \"box.stl\": {\"geo_type\": \"stl\",
#!MFIX-GUI   \"filename\": \"${proj_dir}/box.stl\", \"flipnormals\": false}}, \"tree\": {\"up.stl\": [],
#!MFIX-GUI   \"down.stl\": [], \"box.stl\": []}}
#!MFIX-GUI bc_regions = [[[2], [\"box\"]], [[3], [\"upper belt\"]], [[4], [\"lower
#!MFIX-GUI   belt\"]], [[5], [\"out\"]]]
";
        let g = gui(text);
        let walls = stl_walls(&g, &[2, 3, 4], &only(&["box.stl", "Up.stl", "Down.stl"])).unwrap();
        let got: Vec<(i64, &str, &str, bool)> =
            walls.iter().map(|w| (w.bc, w.name.as_str(), w.file.as_str(), w.flip_normals)).collect();
        assert_eq!(
            got,
            [
                (2, "box", "box.stl", false),
                (3, "upper belt", "Up.stl", false),
                (4, "lower belt", "Down.stl", false)
            ]
        );
        assert!(walls.iter().all(|w| w.scale == 1.0 && w.translate == [0.0; 3] && !w.from_solver_file));
    }

    #[test]
    fn transform_about_the_centre_becomes_grainflows() {
        let text = "\
#!MFIX-GUI regions_dict = {\"regions\": {\"r\": {\"geometry_pool\": [\"a.stl\"], \"type\": \"STL\"}}}
#!MFIX-GUI geometry = {\"geometry_dict\": {\"a.stl\": {\"geo_type\": \"stl\", \"filename\":
#!MFIX-GUI   \"${proj_dir}/a.stl\", \"centerx\": 1.0, \"centery\": 2.0, \"centerz\": {\"__type__\":
#!MFIX-GUI   \"equation\", \"eq\": \"float(zc*2 - 1)\"}, \"scale\": 2.0, \"rotationx\": 90.0,
#!MFIX-GUI   \"rotationz\": 90.0, \"translationx\": 0.5}}, \"tree\": {\"a.stl\": []}}
#!MFIX-GUI bc_regions = [[[7], [\"r\"]]]
#!MFIX-GUI parameters = {\"order\": [\"zc\"], \"parameters\": {\"zc\": 2.0}}
";
        let g = gui(text);
        let w = stl_walls(&g, &[7], &only(&["a.stl"])).unwrap().remove(0);
        assert_eq!((w.scale, w.rotate), (2.0, [90.0, 0.0, 90.0]));
        // The GUI's map, p' = R·(s·(p − c)) + c + T, at a test point, against grainflow's
        // p' = R·(s·p) + t.
        let (c, t_gui, p) = ([1.0, 2.0, 3.0], [0.5, 0.0, 0.0], [0.3, -0.7, 1.1]);
        let gui_map = {
            let r = rotate_xyz([90.0, 0.0, 90.0], [0, 1, 2].map(|k| 2.0 * (p[k] - c[k])));
            [0, 1, 2].map(|k| r[k] + c[k] + t_gui[k])
        };
        let ours = {
            let r = rotate_xyz(w.rotate, p.map(|x| w.scale * x));
            [0, 1, 2].map(|k| r[k] + w.translate[k])
        };
        for k in 0..3 {
            assert!((gui_map[k] - ours[k]).abs() < 1e-12, "{gui_map:?} {ours:?}");
        }
        // Rx(90°) then Rz(90°) takes x to y, y to z (right hand).
        let e = rotate_xyz([90.0, 0.0, 90.0], [1.0, 0.0, 0.0]);
        assert!((e[1] - 1.0).abs() < 1e-15 && e[0].abs() < 1e-15 && e[2].abs() < 1e-15);
        let e = rotate_xyz([90.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        assert!((e[2] - 1.0).abs() < 1e-15);
        // A rotation about a centre the file would have to give is refused.
        let g = gui(&text.replace("\"centerx\": 1.0, ", ""));
        assert!(stl_walls(&g, &[7], &only(&["a.stl"])).unwrap_err().contains("centerx"));
    }

    #[test]
    fn csg_primitives_and_cut_regions_are_refused() {
        let text = "\
#!MFIX-GUI regions_dict = {\"regions\": {\"r\": {\"geometry_pool\": [\"union\"], \"type\": \"STL\"}}}
#!MFIX-GUI geometry = {\"geometry_dict\": {\"box\": {\"geo_type\": \"primitive\", \"type\": \"box\"},
#!MFIX-GUI   \"union\": {\"geo_type\": \"boolean\", \"type\": \"union\"}}, \"tree\": {\"union\": [\"box\"]}}
#!MFIX-GUI bc_regions = [[[3], [\"r\"]]]
";
        let err = stl_walls(&gui(text), &[3], &only(&[])).unwrap_err();
        assert!(
            err.contains("\"union\"") && err.contains("boolean") && err.contains("geometry_NNNN"),
            "{err}"
        );
        let err = stl_walls(&gui(&text.replace("[\"union\"]", "[\"box\"]")), &[3], &only(&[])).unwrap_err();
        assert!(err.contains("\"box\" is a primitive (box)"), "{err}");
        let cut = text.replace("\"type\": \"STL\"", "\"type\": \"STL\", \"stl_shape\": \"box\"");
        assert!(stl_walls(&gui(&cut), &[3], &only(&[])).unwrap_err().contains("stl_shape"));
    }

    #[test]
    fn solver_files_come_first() {
        let g = gui(DRUM);
        let all = ["Tube.stl", "geometry.stl", "geometry_0001.stl", "geometry_0002.stl"];
        let walls = stl_walls(&g, &[1, 2], &only(&all)).unwrap();
        assert_eq!(walls.len(), 2);
        assert_eq!((walls[0].bc, walls[0].file.as_str()), (1, "geometry_0001.stl"));
        assert_eq!((walls[1].bc, walls[1].file.as_str()), (2, "geometry_0002.stl"));
        assert!(walls.iter().all(|w| w.from_solver_file && !w.flip_normals && w.translate == [0.0; 3]));
        // One of them missing: MFIX stops.
        let err = stl_walls(&g, &[1, 2], &only(&["geometry_0001.stl"])).unwrap_err();
        assert!(err.contains("geometry_0002.stl"), "{err}");
        // geometry.stl: for the one CG_ boundary, before the GUI's data.
        let w = stl_walls(&g, &[1], &only(&["geometry.stl", "Tube.stl"])).unwrap();
        assert_eq!((w.len(), w[0].file.as_str(), w[0].from_solver_file), (1, "geometry.stl", true));
        // Several boundaries and the GUI's data: the GUI tells them apart.
        assert!(
            stl_walls(&g, &[1, 2], &only(&["geometry.stl", "Tube.stl"])).unwrap_err().contains("XZ-plane")
        );
        // No GUI data: one wall for all.
        let w = stl_walls(&[], &[4, 5], &only(&["geometry.stl"])).unwrap();
        assert_eq!((w.len(), w[0].bc), (1, 4));
        assert!(stl_walls(&[], &[4], &only(&[])).unwrap_err().contains("geometry_0004.stl"));
        assert!(stl_walls(&[], &[], &only(&[])).unwrap().is_empty());
    }
}
