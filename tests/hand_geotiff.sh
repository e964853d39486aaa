# Sourced by tests/cli_test.sh and fuzz/make_corpus.sh: a small GeoTIFF
# written byte by byte (the engine writes GeoTIFFs only with the georeferencing
# of one it read, and the tests need a first one without GDAL's tools).
#
#   hand_geotiff FILE WIDTH HEIGHT CRS [NODATA]
#
# Little-endian, one uncompressed strip of int16 heights (a slope with a
# ripple, metres), pixels of 30 m from the corner (500000, 5000000). CRS:
# utm32n (EPSG:32632, projected, metres) or wgs84 (EPSG:4326, degrees). With
# NODATA (an integer) the cells on the diagonal hold it and the file declares it.

_le16() { printf "\\x$(printf %02x $(($1 & 255)))\\x$(printf %02x $((($1 >> 8) & 255)))"; }
_le32() { _le16 $(($1 & 65535)); _le16 $((($1 >> 16) & 65535)); }
# an IEEE double given as 16 hex digits, most significant first
_f64() { local h=$1 i; for i in 14 12 10 8 6 4 2 0; do printf "\\x${h:$i:2}"; done; }
_tag() { _le16 "$1"; _le16 "$2"; _le32 "$3"; _le32 "$4"; }  # tag, type, count, value or offset

hand_geotiff() {
  local file=$1 w=$2 h=$3 crs=$4 nodata=${5:-}
  local ntags=13
  [ -n "$nodata" ] && ntags=14
  local ifd_end=$((8 + 2 + ntags * 12 + 4))
  local scale_at=$ifd_end tie_at=$((ifd_end + 24)) keys_at=$((ifd_end + 72)) nodata_at=$((ifd_end + 104))
  local nodata_text="${nodata}"
  local data_at=$((nodata_at + ${#nodata_text} + 2))
  local model=1 key=3072 code=32632  # projected, ProjectedCSTypeGeoKey
  [ "$crs" = wgs84 ] && { model=2; key=2048; code=4326; }  # geographic, GeographicTypeGeoKey
  {
    printf 'II*\x00'; _le32 8
    _le16 $ntags
    _tag 256 3 1 "$w"; _tag 257 3 1 "$h"; _tag 258 3 1 16; _tag 259 3 1 1; _tag 262 3 1 1
    _tag 273 4 1 $data_at; _tag 277 3 1 1; _tag 278 3 1 "$h"; _tag 279 4 1 $((w * h * 2)); _tag 339 3 1 2
    _tag 33550 12 3 $scale_at; _tag 33922 12 6 $tie_at
    _tag 34735 3 16 $keys_at
    [ -n "$nodata" ] && _tag 42113 2 $((${#nodata_text} + 1)) $nodata_at
    _le32 0
    # ModelPixelScale (30, 30, 0); ModelTiepoint raster (0, 0, 0) = model (500000, 5000000, 0)
    _f64 403e000000000000; _f64 403e000000000000; _f64 0000000000000000
    _f64 0000000000000000; _f64 0000000000000000; _f64 0000000000000000
    _f64 411e848000000000; _f64 415312d000000000; _f64 0000000000000000
    # GeoKeyDirectory: version 1.1.0, 3 keys: model type, raster type (pixel is area), the CRS code
    _le16 1; _le16 1; _le16 0; _le16 3
    _le16 1024; _le16 0; _le16 1; _le16 $model
    _le16 1025; _le16 0; _le16 1; _le16 1
    _le16 $key; _le16 0; _le16 1; _le16 $code
    printf '%s\x00\x00' "$nodata_text"
    local x y v
    for ((y = 0; y < h; y++)); do
      for ((x = 0; x < w; x++)); do
        v=$((1000 + 7 * x - 3 * y + (x * y) % 11))
        [ -n "$nodata" ] && [ $x = $y ] && v=$nodata
        _le16 $((v & 65535))
      done
    done
  } >"$file"
}
