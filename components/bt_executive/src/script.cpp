// Script language: tokenizer, recursive-descent parser to an AST, evaluator over Value. See script.hpp.
#include "cairn/bt_executive/script.hpp"

#include <cctype>
#include <cmath>

namespace cairn::bt {

enum class Op : std::uint8_t {
  Literal, Var, Neg, Not, BitNot,
  Add, Sub, Mul, Div, Mod, Concat,
  Eq, Ne, Lt, Le, Gt, Ge, And, Or, BitAnd, BitOr, BitXor,
  Ternary, Assign, AddAssign, SubAssign, MulAssign, DivAssign
};

struct Script::Expr {
  Op op = Op::Literal;
  Value literal;
  int var = -1;
  std::size_t column = 0;
  std::unique_ptr<Expr> a, b, c;
};

namespace {

enum class Tok : std::uint8_t { End, Number, String, Ident, Punct };

struct Token {
  Tok kind = Tok::End;
  std::string text;
  Value value;
  std::size_t column = 0;  // 1-based
};

class Lexer {
 public:
  explicit Lexer(std::string_view s) : s_(s) {}
  std::vector<Token> run() {
    std::vector<Token> out;
    for (;;) {
      while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
      Token t;
      t.column = pos_ + 1;
      if (pos_ >= s_.size()) {
        out.push_back(t);
        return out;
      }
      const char c = s_[pos_];
      if (std::isdigit(static_cast<unsigned char>(c)) ||
          (c == '.' && pos_ + 1 < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_ + 1])))) {
        number(t);
      } else if (std::isalpha(static_cast<unsigned char>(c)) || c == '_' || c == '@') {
        std::size_t b = pos_++;
        while (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_')) ++pos_;
        t.kind = Tok::Ident;
        t.text = std::string(s_.substr(b, pos_ - b));
        if (t.text == "@") throw ScriptError("'@' must be followed by a key", t.column);
      } else if (c == '\'' || c == '"') {
        std::size_t b = ++pos_;
        while (pos_ < s_.size() && s_[pos_] != c) ++pos_;
        if (pos_ >= s_.size()) throw ScriptError("unterminated string", t.column);
        t.kind = Tok::String;
        t.value = Value(std::string(s_.substr(b, pos_ - b)));
        ++pos_;
      } else {
        static constexpr std::string_view two[] = {":=", "+=", "-=", "*=", "/=", "==", "!=", "<=", ">=",
                                                   "&&", "||", ".."};
        t.kind = Tok::Punct;
        for (auto p : two)
          if (s_.substr(pos_, 2) == p) {
            t.text = std::string(p);
            break;
          }
        if (t.text.empty()) {
          static constexpr std::string_view one = "+-*/%<>!~&|^?:();=";
          if (one.find(c) == std::string_view::npos)
            throw ScriptError(std::string("unexpected character '") + c + "'", t.column);
          t.text = std::string(1, c);
        }
        pos_ += t.text.size();
      }
      out.push_back(std::move(t));
    }
  }

 private:
  void number(Token& t) {
    std::size_t b = pos_;
    t.kind = Tok::Number;
    if (s_.substr(pos_, 2) == "0x" || s_.substr(pos_, 2) == "0X") {
      pos_ += 2;
      std::size_t hb = pos_;
      while (pos_ < s_.size() && std::isxdigit(static_cast<unsigned char>(s_[pos_]))) ++pos_;
      std::int64_t v{};
      auto [p, ec] = std::from_chars(s_.data() + hb, s_.data() + pos_, v, 16);
      if (ec != std::errc() || hb == pos_) throw ScriptError("bad hexadecimal number", t.column);
      t.value = Value(v);
      return;
    }
    bool is_float = false;
    while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) ++pos_;
    if (pos_ < s_.size() && s_[pos_] == '.' && !(pos_ + 1 < s_.size() && s_[pos_ + 1] == '.')) {
      is_float = true;
      ++pos_;
      while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) ++pos_;
    }
    if (pos_ < s_.size() && (s_[pos_] == 'e' || s_[pos_] == 'E')) {
      is_float = true;
      ++pos_;
      if (pos_ < s_.size() && (s_[pos_] == '+' || s_[pos_] == '-')) ++pos_;
      std::size_t eb = pos_;
      while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) ++pos_;
      if (eb == pos_) throw ScriptError("bad exponent", t.column);
    }
    if (pos_ < s_.size() && (std::isalpha(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_'))
      throw ScriptError("bad number", t.column);
    std::string_view txt = s_.substr(b, pos_ - b);
    if (is_float) {
      double d{};
      auto [p, ec] = std::from_chars(txt.data(), txt.data() + txt.size(), d);
      if (ec != std::errc()) throw ScriptError("bad number", t.column);
      t.value = Value(d);
    } else {
      std::int64_t v{};
      auto [p, ec] = std::from_chars(txt.data(), txt.data() + txt.size(), v);
      if (ec != std::errc()) throw ScriptError("integer out of range", t.column);
      t.value = Value(v);
    }
  }
  std::string_view s_;
  std::size_t pos_ = 0;
};

using ExprPtr = std::unique_ptr<Script::Expr>;

}  // namespace

class ScriptParser {
 public:
  ScriptParser(std::vector<Token> toks, const ScriptEnums* enums, Script& out)
      : t_(std::move(toks)), enums_(enums), out_(out) {}

  void program() {
    for (;;) {
      while (isPunct(";")) ++i_;
      if (cur().kind == Tok::End) break;
      out_.statements_.push_back(statement());
      if (cur().kind == Tok::End) break;
      if (!isPunct(";")) throw ScriptError("expected ';' or end of script, got '" + describe(cur()) + "'",
                                           cur().column);
    }
  }

 private:
  const Token& cur() const { return t_[i_]; }
  const Token& peek(std::size_t k = 1) const { return t_[std::min(i_ + k, t_.size() - 1)]; }
  bool isPunct(std::string_view p) const { return cur().kind == Tok::Punct && cur().text == p; }
  static std::string describe(const Token& t) {
    switch (t.kind) {
      case Tok::End: return "end of script";
      case Tok::String: return "'" + std::get<std::string>(t.value) + "'";
      case Tok::Number: return valueToString(t.value);
      default: return t.text;
    }
  }
  static ExprPtr make(Op op, std::size_t col) {
    auto e = std::make_unique<Script::Expr>();
    e->op = op;
    e->column = col;
    return e;
  }
  int varIndex(const std::string& name, std::size_t col) {
    for (std::size_t k = 0; k < out_.vars_.size(); ++k)
      if (out_.vars_[k].name == name) return static_cast<int>(k);
    Script::Variable v;
    v.name = name;
    v.column = col;
    out_.vars_.push_back(std::move(v));
    return static_cast<int>(out_.vars_.size() - 1);
  }

  ExprPtr statement() {
    if (cur().kind == Tok::Ident && peek().kind == Tok::Punct) {
      const std::string& p = peek().text;
      Op op{};
      bool assign = true;
      if (p == ":=" || p == "=") op = Op::Assign;
      else if (p == "+=") op = Op::AddAssign;
      else if (p == "-=") op = Op::SubAssign;
      else if (p == "*=") op = Op::MulAssign;
      else if (p == "/=") op = Op::DivAssign;
      else assign = false;
      if (assign) {
        const Token& id = cur();
        if (enums_ && enums_->count(id.text)) throw ScriptError("cannot assign to enum '" + id.text + "'", id.column);
        auto e = make(op, id.column);
        e->var = varIndex(id.text, id.column);
        auto& v = out_.vars_[static_cast<std::size_t>(e->var)];
        if (p == ":=") v.created = true;
        else v.assigned = true;
        if (op != Op::Assign) v.read = true;
        i_ += 2;
        e->a = expr();
        return e;
      }
    }
    return expr();
  }

  ExprPtr expr() {
    auto c = binary(0);
    if (isPunct("?")) {
      auto e = make(Op::Ternary, cur().column);
      ++i_;
      e->a = std::move(c);
      e->b = expr();
      if (!isPunct(":")) throw ScriptError("expected ':' in conditional expression", cur().column);
      ++i_;
      e->c = expr();
      return e;
    }
    return c;
  }

  ExprPtr binary(int level) {
    static const std::vector<std::vector<std::pair<std::string_view, Op>>> levels = {
        {{"||", Op::Or}},
        {{"&&", Op::And}},
        {{"|", Op::BitOr}},
        {{"^", Op::BitXor}},
        {{"&", Op::BitAnd}},
        {{"==", Op::Eq}, {"!=", Op::Ne}},
        {{"<", Op::Lt}, {"<=", Op::Le}, {">", Op::Gt}, {">=", Op::Ge}},
        {{"..", Op::Concat}},
        {{"+", Op::Add}, {"-", Op::Sub}},
        {{"*", Op::Mul}, {"/", Op::Div}, {"%", Op::Mod}},
    };
    if (level == static_cast<int>(levels.size())) return unary();
    auto lhs = binary(level + 1);
    for (;;) {
      if (cur().kind != Tok::Punct) return lhs;
      const Op* found = nullptr;
      for (auto& [txt, op] : levels[static_cast<std::size_t>(level)])
        if (cur().text == txt) found = &op;
      if (!found) return lhs;
      auto e = make(*found, cur().column);
      ++i_;
      e->a = std::move(lhs);
      e->b = binary(level + 1);
      lhs = std::move(e);
    }
  }

  ExprPtr unary() {
    if (isPunct("-") || isPunct("!") || isPunct("~")) {
      auto e = make(isPunct("-") ? Op::Neg : isPunct("!") ? Op::Not : Op::BitNot, cur().column);
      ++i_;
      e->a = unary();
      return e;
    }
    return primary();
  }

  ExprPtr primary() {
    const Token& t = cur();
    switch (t.kind) {
      case Tok::Number:
      case Tok::String: {
        auto e = make(Op::Literal, t.column);
        e->literal = t.value;
        ++i_;
        return e;
      }
      case Tok::Ident: {
        auto e = make(Op::Literal, t.column);
        if (t.text == "true" || t.text == "false") {
          e->literal = Value(t.text == "true");
        } else if (enums_ && enums_->count(t.text)) {
          e->literal = Value(enums_->at(t.text));
        } else {
          e->op = Op::Var;
          e->var = varIndex(t.text, t.column);
          out_.vars_[static_cast<std::size_t>(e->var)].read = true;
        }
        ++i_;
        return e;
      }
      case Tok::Punct:
        if (t.text == "(") {
          ++i_;
          auto e = expr();
          if (!isPunct(")")) throw ScriptError("expected ')', got '" + describe(cur()) + "'", cur().column);
          ++i_;
          return e;
        }
        [[fallthrough]];
      default:
        throw ScriptError("unexpected '" + describe(t) + "'", t.column);
    }
  }

  std::vector<Token> t_;
  std::size_t i_ = 0;
  const ScriptEnums* enums_;
  Script& out_;
};

Script::Script() = default;
Script::~Script() = default;
Script::Script(Script&&) noexcept = default;
Script& Script::operator=(Script&&) noexcept = default;

bool Script::empty() const { return statements_.empty(); }

Script Script::parse(std::string_view code, const ScriptEnums* enums) {
  Script s;
  s.source_ = std::string(code);
  Lexer lex(code);
  ScriptParser p(lex.run(), enums, s);
  p.program();
  if (s.statements_.empty()) throw ScriptError("empty script", 1);
  return s;
}

void Script::bind(Blackboard& bb) {
  for (auto& v : vars_) {
    v.entry = bb.getEntry(v.name);
    if (!v.entry) {
      if (v.created) {
        v.entry = bb.declare(v.name, typeInfo<Value>());
      } else if (v.assigned) {
        throw ScriptError("blackboard entry '" + v.name + "' does not exist (use ':=' to create it)", v.column);
      } else {
        // Read-only and never declared: an untyped entry that stays unset until someone writes it.
        v.entry = bb.declare(v.name, typeInfo<Value>());
      }
    }
    if (!v.entry->type().script_type)
      throw ScriptError("blackboard entry '" + v.name + "' has type " + v.entry->type().name +
                            ", which scripts cannot use",
                        v.column);
  }
}

bool truthy(const Value& v, bool& out) {
  switch (v.index()) {
    case 1: out = std::get<bool>(v); return true;
    case 2: out = std::get<std::int64_t>(v) != 0; return true;
    case 3: out = std::get<double>(v) != 0.0; return true;
    case 4: {
      const auto& s = std::get<std::string>(v);
      if (s == "true") { out = true; return true; }
      if (s == "false") { out = false; return true; }
      return false;
    }
    default: return false;
  }
}

namespace {

struct Eval {
  const std::vector<Script::Variable>& vars;
  std::string* err;

  bool fail(const std::string& m) const {
    if (err) *err = m;
    return false;
  }

  // Numeric view of a value: ints stay ints; numeric strings are parsed (values that came in as text).
  static bool numeric(const Value& v, Value& out) {
    switch (v.index()) {
      case 2:
      case 3: out = v; return true;
      case 4: {
        Value p = parseLiteral(std::get<std::string>(v));
        if (p.index() == 2 || p.index() == 3) {
          out = std::move(p);
          return true;
        }
        return false;
      }
      default: return false;
    }
  }
  static double asDouble(const Value& v) {
    return v.index() == 2 ? static_cast<double>(std::get<std::int64_t>(v)) : std::get<double>(v);
  }

  bool arith(Op op, const Value& x, const Value& y, Value& out) const {
    if (op == Op::Add && x.index() == 4 && y.index() == 4) {
      out = Value(std::get<std::string>(x) + std::get<std::string>(y));
      return true;
    }
    Value a, b;
    if (!numeric(x, a) || !numeric(y, b))
      return fail(std::string("arithmetic on ") + std::string(valueTypeName(x)) + " and " +
                  std::string(valueTypeName(y)));
    if (a.index() == 2 && b.index() == 2) {
      const std::int64_t i = std::get<std::int64_t>(a), j = std::get<std::int64_t>(b);
      switch (op) {
        case Op::Add: out = Value(i + j); return true;
        case Op::Sub: out = Value(i - j); return true;
        case Op::Mul: out = Value(i * j); return true;
        case Op::Div:
          if (j == 0) return fail("integer division by zero");
          out = Value(i / j);
          return true;
        case Op::Mod:
          if (j == 0) return fail("integer modulo by zero");
          out = Value(i % j);
          return true;
        default: return fail("bad operator");
      }
    }
    const double p = asDouble(a), q = asDouble(b);
    switch (op) {
      case Op::Add: out = Value(p + q); return true;
      case Op::Sub: out = Value(p - q); return true;
      case Op::Mul: out = Value(p * q); return true;
      case Op::Div:
        if (q == 0.0) return fail("division by zero");
        out = Value(p / q);
        return true;
      case Op::Mod: out = Value(std::fmod(p, q)); return true;
      default: return fail("bad operator");
    }
  }

  bool compare(Op op, const Value& x, const Value& y, Value& out) const {
    int c = 0;
    bool comparable = true;
    if (x.index() == 0 || y.index() == 0) return fail("comparison with an unset value");
    if (x.index() == 4 && y.index() == 4) {
      c = std::get<std::string>(x).compare(std::get<std::string>(y));
    } else if (x.index() == 1 && y.index() == 1) {
      c = int(std::get<bool>(x)) - int(std::get<bool>(y));
    } else {
      auto num = [](const Value& v, Value& o) {
        if (v.index() == 1) {
          o = Value(std::int64_t(std::get<bool>(v)));
          return true;
        }
        return numeric(v, o);
      };
      Value a, b;
      if (!num(x, a) || !num(y, b)) {
        comparable = false;
      } else if (a.index() == 2 && b.index() == 2) {
        auto i = std::get<std::int64_t>(a), j = std::get<std::int64_t>(b);
        c = i < j ? -1 : i > j ? 1 : 0;
      } else {
        double p = asDouble(a), q = asDouble(b);
        c = p < q ? -1 : p > q ? 1 : 0;
      }
    }
    if (!comparable) {
      if (op == Op::Eq) { out = Value(false); return true; }
      if (op == Op::Ne) { out = Value(true); return true; }
      return fail(std::string("cannot order ") + std::string(valueTypeName(x)) + " and " +
                  std::string(valueTypeName(y)));
    }
    bool r = false;
    switch (op) {
      case Op::Eq: r = c == 0; break;
      case Op::Ne: r = c != 0; break;
      case Op::Lt: r = c < 0; break;
      case Op::Le: r = c <= 0; break;
      case Op::Gt: r = c > 0; break;
      case Op::Ge: r = c >= 0; break;
      default: break;
    }
    out = Value(r);
    return true;
  }

  bool boolOf(const Script::Expr& e, bool& b) const {
    Value v;
    if (!run(e, v)) return false;
    if (!truthy(v, b)) return fail(std::string("expected a boolean, got ") + std::string(valueTypeName(v)));
    return true;
  }

  bool intOf(const Value& v, std::int64_t& i) const {
    if (v.index() == 2) {
      i = std::get<std::int64_t>(v);
      return true;
    }
    return fail("bitwise operator needs integers");
  }

  bool run(const Script::Expr& e, Value& out) const {
    switch (e.op) {
      case Op::Literal: out = e.literal; return true;
      case Op::Var: {
        const auto& var = vars[static_cast<std::size_t>(e.var)];
        if (!var.entry) return fail("script not bound");
        if (!var.entry->getValue(out)) return fail("blackboard entry '" + var.name + "' is unset");
        return true;
      }
      case Op::Neg: {
        Value v, n;
        if (!run(*e.a, v)) return false;
        if (!numeric(v, n)) return fail("unary '-' on " + std::string(valueTypeName(v)));
        out = n.index() == 2 ? Value(-std::get<std::int64_t>(n)) : Value(-std::get<double>(n));
        return true;
      }
      case Op::Not: {
        bool b;
        if (!boolOf(*e.a, b)) return false;
        out = Value(!b);
        return true;
      }
      case Op::BitNot: {
        Value v;
        std::int64_t i;
        if (!run(*e.a, v) || !intOf(v, i)) return false;
        out = Value(~i);
        return true;
      }
      case Op::And:
      case Op::Or: {
        bool b;
        if (!boolOf(*e.a, b)) return false;
        if ((e.op == Op::And && !b) || (e.op == Op::Or && b)) {
          out = Value(b);
          return true;
        }
        if (!boolOf(*e.b, b)) return false;
        out = Value(b);
        return true;
      }
      case Op::Ternary: {
        bool b;
        if (!boolOf(*e.a, b)) return false;
        return run(b ? *e.b : *e.c, out);
      }
      case Op::Assign:
      case Op::AddAssign:
      case Op::SubAssign:
      case Op::MulAssign:
      case Op::DivAssign: {
        const auto& var = vars[static_cast<std::size_t>(e.var)];
        if (!var.entry) return fail("script not bound");
        Value rhs;
        if (!run(*e.a, rhs)) return false;
        if (e.op != Op::Assign) {
          Value old;
          if (!var.entry->getValue(old)) return fail("blackboard entry '" + var.name + "' is unset");
          Op bop = e.op == Op::AddAssign ? Op::Add : e.op == Op::SubAssign ? Op::Sub
                   : e.op == Op::MulAssign ? Op::Mul : Op::Div;
          Value r;
          if (!arith(bop, old, rhs, r)) return false;
          rhs = std::move(r);
        }
        if (!var.entry->setValue(rhs))
          return fail("cannot assign " + std::string(valueTypeName(rhs)) + " to blackboard entry '" + var.name +
                      "' of type " + var.entry->type().name);
        out = std::move(rhs);
        return true;
      }
      default: break;
    }
    Value x, y;
    if (!run(*e.a, x) || !run(*e.b, y)) return false;
    switch (e.op) {
      case Op::Add:
      case Op::Sub:
      case Op::Mul:
      case Op::Div:
      case Op::Mod: return arith(e.op, x, y, out);
      case Op::Concat: out = Value(valueToString(x) + valueToString(y)); return true;
      case Op::Eq:
      case Op::Ne:
      case Op::Lt:
      case Op::Le:
      case Op::Gt:
      case Op::Ge: return compare(e.op, x, y, out);
      case Op::BitAnd:
      case Op::BitOr:
      case Op::BitXor: {
        std::int64_t i, j;
        if (!intOf(x, i) || !intOf(y, j)) return false;
        out = Value(e.op == Op::BitAnd ? (i & j) : e.op == Op::BitOr ? (i | j) : (i ^ j));
        return true;
      }
      default: return fail("bad expression");
    }
  }
};

}  // namespace

bool Script::evaluate(Value& result, std::string* err) const {
  Eval ev{vars_, err};
  for (const auto& st : statements_)
    if (!ev.run(*st, result)) return false;
  return true;
}

bool Script::evaluateBool(bool& result, std::string* err) const {
  Value v;
  if (!evaluate(v, err)) return false;
  if (!truthy(v, result)) {
    if (err) *err = std::string("script result is not a boolean (") + std::string(valueTypeName(v)) + ")";
    return false;
  }
  return true;
}

}  // namespace cairn::bt
