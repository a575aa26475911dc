//! The shared space in Lua: `troupe.wall{…}`, `troupe.floor{…}` and
//! `troupe.path(from, to[, { radius }])`, and `troupe.deepest_overlap([{ discs }])`.

use crate::args::{check_keys, err, floor_point, opt_number, table_arg};
use crate::stage::stage;
use mlua::{Lua, Table, Value};
use troupe_body::glam::DVec2;
use troupe_body::template::template;
use troupe_scene::collision::Other;
use troupe_scene::space::{body_radius, Floor, Wall};

/// Reads a list of floor points `{{x, z}, …}` for `method`.
fn polygon(v: &Value, method: &str, what: &str) -> mlua::Result<Vec<DVec2>> {
    let Value::Table(list) = v else {
        return Err(err(
            method,
            format!("{what} must be a list of points {{{{x, z}}, …}}"),
        ));
    };
    list.sequence_values::<Value>()
        .enumerate()
        .map(|(i, p)| floor_point(&p?, method, &format!("{what}[{}]", i + 1)))
        .collect()
}

/// The radius of an adult of the default size, for path queries that give none.
fn default_radius() -> mlua::Result<f64> {
    let adult = template("adult").map_err(|e| err("path", e))?;
    let skeleton = adult
        .instantiate(adult.default_params())
        .map_err(|e| err("path", e))?;
    Ok(body_radius(&skeleton))
}

/// Adds `wall`, `floor` and `path` to the `troupe` table.
pub(crate) fn install(lua: &Lua, troupe: &Table) -> mlua::Result<()> {
    troupe.set(
        "wall",
        lua.create_function(|lua, args: mlua::MultiValue| {
            let t = table_arg("wall", args)?;
            check_keys(&t, "wall", &["from", "to", "thickness", "height"])?;
            let wall = Wall {
                from: floor_point(&t.get("from")?, "wall", "`from`")?,
                to: floor_point(&t.get("to")?, "wall", "`to`")?,
                thickness: opt_number(&t, "wall", "thickness")?.unwrap_or(0.1),
                height: opt_number(&t, "wall", "height")?.unwrap_or(2.5),
            };
            stage(lua)?.scene.add_wall(wall).map_err(|e| err("wall", e))
        })?,
    )?;
    troupe.set(
        "floor",
        lua.create_function(|lua, args: mlua::MultiValue| {
            let t = table_arg("floor", args)?;
            check_keys(&t, "floor", &["outline", "holes"])?;
            let outline = polygon(&t.get("outline")?, "floor", "`outline`")?;
            let holes = match t.get::<Value>("holes")? {
                Value::Nil => Vec::new(),
                Value::Table(list) => list
                    .sequence_values::<Value>()
                    .enumerate()
                    .map(|(i, h)| polygon(&h?, "floor", &format!("`holes`[{}]", i + 1)))
                    .collect::<mlua::Result<_>>()?,
                other => {
                    return Err(err(
                        "floor",
                        format!(
                            "`holes` must be a list of polygons, got {}",
                            other.type_name()
                        ),
                    ))
                }
            };
            stage(lua)?
                .scene
                .set_floor(Floor { outline, holes })
                .map_err(|e| err("floor", e))
        })?,
    )?;
    troupe.set(
        "deepest_overlap",
        lua.create_function(|lua, options: Option<Table>| {
            let discs = match &options {
                Some(o) => {
                    check_keys(o, "deepest_overlap", &["discs"])?;
                    o.get::<Option<bool>>("discs")?.unwrap_or(false)
                }
                None => false,
            };
            let stage = stage(lua)?;
            let actors = stage.scene.actors();
            let name = |i: usize| Some(actors[i].name.clone());
            if discs {
                return Ok(match stage.scene.deepest_overlap() {
                    Some((depth, i, j)) => (depth, name(i), name(j), None, None),
                    None => (0.0, None, None, None, None),
                });
            }
            let solid = |i: usize, k: usize| Some(actors[i].skeleton.solids()[k].1.name.clone());
            Ok(match stage.scene.deepest_interpenetration() {
                Some(found) => {
                    let (other, other_solid) = match found.other {
                        Other::Actor { actor, solid: k } => (name(actor), solid(actor, k)),
                        Other::Obstacle(obstacle) => (Some(obstacle), None),
                    };
                    (
                        found.depth,
                        name(found.actor),
                        other,
                        solid(found.actor, found.solid),
                        other_solid,
                    )
                }
                None => (0.0, None, None, None, None),
            })
        })?,
    )?;
    troupe.set(
        "path",
        lua.create_function(|lua, (from, to, options): (Value, Value, Option<Table>)| {
            let from = floor_point(&from, "path", "`from`")?;
            let to = floor_point(&to, "path", "`to`")?;
            let radius = match &options {
                Some(o) => {
                    check_keys(o, "path", &["radius"])?;
                    opt_number(o, "path", "radius")?
                }
                None => None,
            };
            let radius = match radius {
                Some(r) if r.is_finite() && (0.0..=5.0).contains(&r) => r,
                Some(r) => {
                    return Err(err(
                        "path",
                        format!("`radius` must be in [0, 5] m, got {r}"),
                    ))
                }
                None => default_radius()?,
            };
            let found = stage(lua)?.scene.world().path(from, to, radius);
            match found {
                Ok(points) => {
                    let list = lua.create_table()?;
                    for p in std::iter::once(from).chain(points) {
                        list.push(lua.create_sequence_from([p.x, p.y])?)?;
                    }
                    Ok((Value::Table(list), Value::Nil))
                }
                Err(why) => Ok((
                    Value::Nil,
                    Value::String(lua.create_string(why.to_string())?),
                )),
            }
        })?,
    )?;
    Ok(())
}
