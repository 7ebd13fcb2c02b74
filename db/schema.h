// The database schema as an ordered list of migrations. Migration i takes a
// database from schema version i to i+1; a database is upgraded in place on
// open. Never edit a released migration: append a new one.
#pragma once

#include <string>
#include <vector>

namespace doasido::db {

const std::vector<std::string>& Migrations();

}  // namespace doasido::db
