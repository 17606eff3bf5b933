// The small expression language of Script / ScriptCondition nodes and of the _skipIf/_failureIf/_successIf/_while
// preconditions and _onSuccess/_onFailure/_onHalted/_post postconditions (BehaviorTree.CPP v4 scripting subset).
//
//   program    := statement (';' statement)* [';']
//   statement  := IDENT (':=' | '=' | '+=' | '-=' | '*=' | '/=') expr | expr
//   expr       := or ['?' expr ':' expr]
//   or := and ('||' and)*     and := bitor ('&&' bitor)*     bitor := bitxor ('|' bitxor)*
//   bitxor := bitand ('^' bitand)*   bitand := equality ('&' equality)*
//   equality := relational (('=='|'!=') relational)*   relational := concat (('<'|'<='|'>'|'>=') concat)*
//   concat := additive ('..' additive)*   additive := term (('+'|'-') term)*   term := unary (('*'|'/'|'%') unary)*
//   unary := ('-'|'!'|'~') unary | primary
//   primary := NUMBER | 'string' | "string" | true | false | IDENT | ENUM | '(' expr ')'
//
// Identifiers are blackboard keys (resolved to entries when the tree is loaded; '@key' is the root scope).
// ':=' creates the entry (untyped if no typed port declares it), '=' requires an existing entry.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "cairn/bt_executive/blackboard.hpp"
#include "cairn/bt_executive/value.hpp"

namespace cairn::bt {

using ScriptEnums = std::unordered_map<std::string, std::int64_t>;

/// Syntax or binding error; `column` is 1-based within the script text (0 = not position-specific).
struct ScriptError : std::runtime_error {
  ScriptError(const std::string& what, std::size_t col) : std::runtime_error(what), column(col) {}
  std::size_t column;
};

class Script {
 public:
  struct Variable {
    std::string name;
    bool created = false;   ///< target of ':='
    bool assigned = false;  ///< target of '=', '+=', ...
    bool read = false;
    std::size_t column = 0;
    std::shared_ptr<EntryBase> entry;  ///< set by bind()
  };

  Script();
  ~Script();
  Script(Script&&) noexcept;
  Script& operator=(Script&&) noexcept;

  /// Parses `code`; throws ScriptError with the column of the offending token.
  static Script parse(std::string_view code, const ScriptEnums* enums = nullptr);

  const std::vector<Variable>& variables() const { return vars_; }
  const std::string& source() const { return source_; }
  bool empty() const;

  /// Resolves every variable to a blackboard entry (load time). Throws ScriptError if a variable does not exist,
  /// or is not a script type.
  void bind(Blackboard& bb);

  /// Evaluates the program; the result is the value of the last statement. Returns false and fills `err` on a
  /// run-time error (unset variable, type error, division by zero). Does not allocate for numeric programs.
  bool evaluate(Value& result, std::string* err = nullptr) const;
  /// evaluate() + truthiness of the result.
  bool evaluateBool(bool& result, std::string* err = nullptr) const;

  struct Expr;

 private:
  std::string source_;
  std::vector<std::unique_ptr<Expr>> statements_;
  std::vector<Variable> vars_;
  friend class ScriptParser;
};

/// Truthiness used by conditions: bool, numbers != 0, strings "true"/"false"; false for anything else.
bool truthy(const Value& v, bool& out);

}  // namespace cairn::bt
