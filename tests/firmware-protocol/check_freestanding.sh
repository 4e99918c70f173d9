#!/usr/bin/env bash
# Fails if the freestanding protocol objects need any symbol besides memcpy/memset and their own.
set -eu
objs=$(echo "$1" | tr ';' ' ')
defined=$(nm --defined-only $objs | awk 'NF==3{print $3}' | sort -u)
undef=$(nm -u $objs | awk '/ U /{print $2}' | sort -u)
bad=$(comm -23 <(echo "$undef") <(printf '%s\n' $defined memcpy memset | sort -u) | grep -v '^$' || true)
if [ -n "$bad" ]; then echo "freestanding protocol needs: $bad"; exit 1; fi
echo "freestanding objects need only: $(comm -12 <(echo "$undef") <(printf 'memcpy\nmemset\n') | tr '\n' ' ')"
